#include "core/collision_detection.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/world.hpp"

namespace softbake {

namespace {
constexpr std::size_t kPairGrain = 256;

TriangleCorners corners(const World& world, Index triangle) {
  const Triangle& t = world.collision.triangleVertices[triangle];
  return {collisionVertex(world, t[0]), collisionVertex(world, t[1]), collisionVertex(world, t[2])};
}

const Vec3& previousCollisionVertex(const World& world, Index v) {
  return v < world.collision.particleCount
             ? world.previousPosition[v]
             : world.collision.staticVertex[v - world.collision.particleCount];
}

bool hasVertex(const Triangle& t, Index v) {
  return t[0] == v || t[1] == v || t[2] == v;
}

/// Tests particle p's motion against `triangle`. The triangle moved too during the substep: the
/// particle's start is shifted by the triangle's own displacement (of its centroid), so the test
/// sees the motion relative to the triangle. Without that, two bodies closing in on each other
/// faster than the skin per substep would meet with each particle's start already behind the
/// other's new surface, and the crossing would go unseen. Exact for a translating triangle; for a
/// rotating or stretching one, edge contacts catch what is left.
bool testParticle(const World& world, Index p, Index triangle, ParticleContact& contact) {
  const CollisionGeometry& geometry = world.collision;
  const Triangle& t = geometry.triangleVertices[triangle];
  const TriangleCorners now = corners(world, triangle);
  Vec3 displacement = Vec3::Zero();
  for (int k = 0; k < 3; ++k) displacement += now[k] - previousCollisionVertex(world, t[k]);
  const Vec3 start = world.previousPosition[p] + displacement / Scalar(3);
  const Vec3& end = world.position[p];
  if (!intersectSegmentTriangle(start, end, now[0], now[1], now[2], contact.hit)) return false;

  const Vec3 normal = (now[1] - now[0]).cross(now[2] - now[0]);
  const Scalar startSide = normal.dot(start - now[0]), endSide = normal.dot(end - now[0]);
  Scalar orientation;
  if (geometry.surfaceClosed[geometry.triangleSurface[triangle]]) {
    // A closed surface has an outside: only entering counts. A particle on its way out (left
    // inside by an earlier step) must not be pushed back in.
    if (!(startSide >= 0 && endSide < 0)) return false;
    orientation = 1;
  } else {
    orientation = startSide > 0 || (startSide == 0 && endSide < 0) ? Scalar(1) : Scalar(-1);
  }
  contact.particle = p;
  contact.triangle = triangle;
  contact.normal = orientation * normal.normalized();
  return true;
}
}  // namespace

const Vec3& collisionVertex(const World& world, Index v) {
  return v < world.collision.particleCount
             ? world.position[v]
             : world.collision.staticVertex[v - world.collision.particleCount];
}

CollisionDetector::CollisionDetector(const CollisionSettings& settings)
    : broadPhase_(
          makeBroadPhase(settings.broadPhase, {.subdivisionLevels = settings.subdivisionLevels})) {}

void CollisionDetector::sortUniqueCandidates(std::size_t particleCount) {
  // A counting sort by particle (dense indices, a few candidates each), then each particle's
  // handful of triangles by insertion sort: the order of sorting the (particle, triangle) pairs,
  // in linear time. A comparison sort of them was a quarter of a contact-heavy step.
  particleBucketEnd_.assign(particleCount + 1, 0);
  for (const ParticleCandidate& c : unsortedCandidates_) ++particleBucketEnd_[c.particle + 1];
  for (std::size_t p = 0; p < particleCount; ++p)
    particleBucketEnd_[p + 1] += particleBucketEnd_[p];
  particleCandidates_.resize(unsortedCandidates_.size());
  for (const ParticleCandidate& c : unsortedCandidates_)
    particleCandidates_[particleBucketEnd_[c.particle]++] = c;
  // Each bucket p now ends at particleBucketEnd_[p] and starts where bucket p − 1 ends.
  std::size_t kept = 0, begin = 0;
  for (std::size_t p = 0; p < particleCount; ++p) {
    const std::size_t end = particleBucketEnd_[p];
    const std::size_t first = kept;
    for (std::size_t i = begin; i < end; ++i) {
      // Compacting in place: kept <= i, so nothing unread is overwritten.
      const ParticleCandidate c = particleCandidates_[i];
      std::size_t j = kept;
      while (j > first && particleCandidates_[j - 1].triangle > c.triangle) --j;
      if (j > first && particleCandidates_[j - 1].triangle == c.triangle) continue;  // duplicate
      for (std::size_t k = kept; k > j; --k) particleCandidates_[k] = particleCandidates_[k - 1];
      particleCandidates_[j] = c;
      ++kept;
    }
    begin = end;
  }
  particleCandidates_.resize(kept);
}

void CollisionDetector::detect(const World& world, StageClock* clock) {
  const CollisionGeometry& geometry = world.collision;
  broadPhase_->findPairs(geometry.broadPhaseInput(), pairs_);
  if (clock) clock->lap(Stage::BroadPhase);

  // Edge contacts: the multi-pass test on every candidate pair, one slot per pair.
  pairHits_.resize(pairs_.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs_.size(), kPairGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                        intersectTrianglePair(corners(world, pairs_[i].first),
                                              corners(world, pairs_[i].second), pairHits_[i]);
                    });
  edgeContacts_.clear();
  for (std::size_t i = 0; i < pairs_.size(); ++i) {
    const TrianglePairHits& hits = pairHits_[i];
    for (int k = 0; k < hits.firstCount; ++k)
      edgeContacts_.push_back(
          {pairs_[i].first, pairs_[i].second, hits.firstEdges[k].edge, hits.firstEdges[k].hit});
    for (int k = 0; k < hits.secondCount; ++k)
      edgeContacts_.push_back(
          {pairs_[i].second, pairs_[i].first, hits.secondEdges[k].edge, hits.secondEdges[k].hit});
  }

  // Particle contacts: every free particle of one triangle of a pair against the other triangle.
  // A particle belongs to several triangles, so the same (particle, triangle) comes from several
  // pairs: sorted and made unique before testing.
  unsortedCandidates_.clear();
  auto addCorners = [&](Index from, Index against) {
    if (!geometry.surfaces[geometry.triangleSurface[from]].moving) return;
    const Triangle& target = geometry.triangleVertices[against];
    for (Index p : geometry.triangleVertices[from])
      if (world.inverseMass[p] != 0 && !hasVertex(target, p))
        unsortedCandidates_.push_back({p, against});
  };
  for (const TrianglePair& pair : pairs_) {
    addCorners(pair.first, pair.second);
    addCorners(pair.second, pair.first);
  }
  sortUniqueCandidates(world.particleCount());

  particleHit_.resize(particleCandidates_.size());
  particleSlots_.resize(particleCandidates_.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, particleCandidates_.size(), kPairGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                        particleHit_[i] =
                            testParticle(world, particleCandidates_[i].particle,
                                         particleCandidates_[i].triangle, particleSlots_[i]);
                    });
  particleContacts_.clear();
  for (std::size_t i = 0; i < particleCandidates_.size(); ++i)
    if (particleHit_[i]) particleContacts_.push_back(particleSlots_[i]);
  // Candidates were sorted by particle, so each particle's contacts are adjacent; within one
  // particle, the earliest crossing comes first, ties kept in triangle order. The groups are a
  // handful of contacts: an insertion sort, which is stable and, unlike std::stable_sort,
  // allocates nothing.
  for (std::size_t i = 1; i < particleContacts_.size(); ++i) {
    const ParticleContact contact = particleContacts_[i];
    std::size_t j = i;
    for (; j > 0 && particleContacts_[j - 1].particle == contact.particle &&
           particleContacts_[j - 1].hit.t > contact.hit.t;
         --j)
      particleContacts_[j] = particleContacts_[j - 1];
    particleContacts_[j] = contact;
  }
  if (clock) clock->lap(Stage::NarrowPhase);
}

}  // namespace softbake
