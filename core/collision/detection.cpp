#include "core/collision/detection.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

namespace {
/// Removes from `pairs` those of `drop`; both are sorted. One walk along the two, where a search
/// per pair cost an assembly's step more than its broad phase's filter.
void dropSortedPairs(std::span<const TrianglePair> drop, std::vector<TrianglePair>& pairs) {
  if (drop.empty()) return;
  auto next = drop.begin();
  std::size_t kept = 0;
  for (const TrianglePair& pair : pairs) {
    while (next != drop.end() && *next < pair) ++next;
    if (next == drop.end() || !(*next == pair)) pairs[kept++] = pair;
  }
  pairs.resize(kept);
}

/// Chunks of pairs for the narrow phase: enough for TBB to balance uneven chunks.
constexpr std::size_t kPairChunks = 128;

/// The struck triangle of a particle test, computed once for all the particles tested against it.
/// The triangle moved too during the substep: a particle's start is shifted by the triangle's own
/// displacement (of its centroid), so the test sees the motion relative to the triangle. Without
/// that, two bodies closing in on each other faster than the skin per substep would meet with each
/// particle's start already behind the other's new surface, and the crossing would go unseen.
/// Exact for a translating triangle; for a rotating or stretching one, edge contacts catch what is
/// left.
///
/// An open surface (a sheet) bends and stretches under what it catches, where the centroid's shift
/// is a poor model of its motion: a particle could pass through it unseen, and an open surface has
/// no inside from which an edge push could bring the particle back. So against an open surface a
/// particle also counts as crossing when it changed sides of the triangle's plane between the
/// substep's start (the triangle where it was then) and its end, with its end over the triangle,
/// and no further from the plane than its motion relative to the triangle's corners reaches.
/// That bound holds for any crossing (a point that met the triangle at some time in the substep
/// lies, at its end, within the largest of those relative motions of a point of the triangle),
/// and a plane that merely turned over does not meet it. A sliver of a CAD part (59 mm long, its
/// two short edges all but adding up to its long one) turned over as its corners moved 1.5 mm,
/// and a particle 0.23 m in front of it "changed sides": the response moved a light corner of the
/// sliver 0.23 m towards it, 178 J in its springs, on an engine lying still.
struct ParticleTarget {
  Index triangle;
  TriangleCorners now;
  Vec3 shift;                        ///< the centroid's displacement over the substep
  Vec3 normal;                       ///< unnormalised, as intersectSegmentTriangle computes it
  bool open;                         ///< the triangle's surface is open
  Vec3 startCorner, startNormal;     ///< corner 0 and normal at the substep's start (open only)
  std::array<Vec3, 3> cornerMotion;  ///< each corner's displacement over the substep
};

/// `now` and `normal`: the triangle's corners at the substep's end and their triangleNormal().
ParticleTarget particleTarget(const CollisionGeometry& geometry, const SubstepMotion& motion,
                              Index triangle, const TriangleCorners& now, const Vec3& normal) {
  const Triangle& t = geometry.triangleVertices[triangle];
  ParticleTarget target{triangle,
                        now,
                        Vec3::Zero(),
                        normal,
                        !geometry.surfaceClosed[geometry.triangleSurface[triangle]],
                        Vec3::Zero(),
                        Vec3::Zero(),
                        {}};
  Vec3 displacement = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    target.cornerMotion[k] = target.now[k] - geometry.vertex(motion.start, t[k]);
    displacement += target.cornerMotion[k];
  }
  target.shift = displacement / Scalar(3);
  if (target.open) {
    const TriangleCorners then = geometry.corners(motion.start, triangle);
    target.startCorner = then[0];
    target.startNormal = (then[1] - then[0]).cross(then[2] - then[0]);
  }
  return target;
}

/// The sides of the triangle's plane particle p was on at the substep's start (against the
/// triangle then) and is on at its end (against the triangle now).
std::pair<Scalar, Scalar> sidesAcrossTheStep(const SubstepMotion& motion, Index p,
                                             const ParticleTarget& target) {
  return {target.startNormal.dot(motion.start[p] - target.startCorner),
          target.normal.dot(motion.end[p] - target.now[0])};
}

bool changedSides(const std::pair<Scalar, Scalar>& sides) {
  return (sides.first > 0 && sides.second < 0) || (sides.first < 0 && sides.second > 0);
}

/// The sides of the target's plane that particle p's shifted motion starts and ends on, as
/// intersectSegmentTriangle computes them.
struct ParticleSides {
  Scalar start, end;
};

/// `endSide`: the side of the target's plane p ends on, sidesOfPlane() of its triangle.
ParticleSides particleSides(const SubstepMotion& motion, Index p, const ParticleTarget& target,
                            Scalar endSide) {
  const Vec3 start = motion.start[p] + target.shift;
  return {target.normal.dot(start - target.now[0]), endSide};
}

/// False when particle p's shifted motion stays strictly on one side of the target's plane (or on
/// it): intersectSegmentTriangle's own first rejection, so skipping the test then changes nothing.
/// Most candidates end here.
bool mayCross(const SubstepMotion& motion, Index p, const ParticleTarget& target,
              const ParticleSides& sides) {
  return (!((sides.start > 0 && sides.end > 0) || (sides.start < 0 && sides.end < 0)) &&
          sides.start != sides.end) ||
         (target.open && changedSides(sidesAcrossTheStep(motion, p, target)));
}

/// Against an open surface: p changed sides of the triangle across the substep and ends over it.
/// The hit is where its end projects onto the triangle, on the side it came from: the line–triangle
/// test on the end's segment to its mirror image through the plane, which crosses the plane there.
bool crossedOpenSurface(const SubstepMotion& motion, Index p, const ParticleTarget& target,
                        ParticleContact& contact) {
  const std::pair<Scalar, Scalar> sides = sidesAcrossTheStep(motion, p, target);
  if (!changedSides(sides)) return false;
  const Scalar area2 = target.normal.squaredNorm();
  if (!(area2 > 0)) return false;
  const Vec3 own = motion.end[p] - motion.start[p];
  Scalar reach2 = 0;
  for (const Vec3& corner : target.cornerMotion)
    reach2 = std::max(reach2, (own - corner).squaredNorm());
  if (sides.second * sides.second > reach2 * area2) return false;
  const Vec3& end = motion.end[p];
  const Vec3 mirror = end - (2 * sides.second / area2) * target.normal;
  const TriangleCorners& now = target.now;
  if (!intersectSegmentTriangle(end, mirror, now[0], now[1], now[2], contact.hit)) return false;
  contact.hit.t = sides.first / (sides.first - sides.second);  // along the particle's own motion
  contact.particle = p;
  contact.triangle = target.triangle;
  contact.normal = (sides.first > 0 ? Scalar(1) : Scalar(-1)) * target.normal.normalized();
  return true;
}

/// Tests particle p's motion against the target triangle.
bool testParticle(const CollisionGeometry& geometry, const SubstepMotion& motion, Index p,
                  const ParticleTarget& target, const ParticleSides& sides,
                  ParticleContact& contact) {
  const Index triangle = target.triangle;
  const TriangleCorners& now = target.now;
  const Vec3& normal = target.normal;
  if (!intersectSegmentTriangle(motion.start[p] + target.shift, motion.end[p], now[0], now[1],
                                now[2], normal, sides.start, sides.end, contact.hit))
    return target.open && crossedOpenSurface(motion, p, target, contact);

  const Scalar startSide = sides.start, endSide = sides.end;
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

CollisionDetector::CollisionDetector(const CollisionSettings& settings)
    : broadPhase_(
          makeBroadPhase(settings.broadPhase, {.subdivisionLevels = settings.subdivisionLevels})) {
  if (settings.pairCache) pairCache_.emplace();
}

void CollisionDetector::ignoreOverlaps(const InitialOverlaps& overlaps) {
  ignoredSurfaces_ = overlappingSurfaces(overlaps);
}

void CollisionDetector::dropIgnoredPairs(const CollisionGeometry& geometry,
                                         std::vector<TrianglePair>& pairs) const {
  dropSurfacePairs(geometry, ignoredSurfaces_, pairs);
  dropSortedPairs(setAside_, pairs);
}

void CollisionDetector::dropLeftAlone(const CollisionGeometry& geometry,
                                      std::vector<TrianglePair>& pairs) const {
  dropIgnoredPairs(geometry, pairs);
  dropSortedPairs(fitted_, pairs);
}

void CollisionDetector::detect(const SceneTopology& topology, const CollisionGeometry& geometry,
                               const SubstepMotion& motion, StageClock* clock) {
  updateCollisionBoxes(topology, geometry, motion, boxes_, topology.settings.skin, particleBoxes_);
  updateFlatPatches(geometry, motion.start, motion.end, patchFlat_);
  if (clock) clock->lap(Stage::Boxes);
  if (pairCache_)
    pairCache_->findPairs(*broadPhase_, geometry.broadPhaseInput(boxes_, &patchFlat_), pairs_);
  else
    broadPhase_->findPairs(geometry.broadPhaseInput(boxes_, &patchFlat_), pairs_);
  dropLeftAlone(geometry, pairs_);
  if (clock) clock->lap(Stage::BroadPhase);
  findContacts(topology, geometry, motion);
  if (clock) clock->lap(Stage::NarrowPhase);
}

void CollisionDetector::dropTangledContacts(const SceneTopology& topology,
                                            const CollisionGeometry& geometry,
                                            const SubstepMotion& motion) {
  TrianglePairHits hits;
  const auto intersectedAtStart = [&](Index t, Index u) {
    return geometry.trianglesCross(motion.start, t, u, hits);
  };
  std::erase_if(edgeContacts_, [&](const EdgeContact& contact) {
    return intersectedAtStart(contact.edgeTriangle, contact.triangle);
  });
  std::erase_if(particleContacts_, [&](const ParticleContact& contact) {
    for (Index r = topology.triangleRowStart[contact.particle];
         r < topology.triangleRowStart[contact.particle + 1]; ++r)
      if (intersectedAtStart(topology.triangleRefs[r], contact.triangle)) return true;
    return false;
  });
}

void CollisionDetector::findContacts(const SceneTopology& topology,
                                     const CollisionGeometry& geometry,
                                     const SubstepMotion& motion) {
  // Per pair, both tests at once: the multi-pass test on the two triangles (edge contacts), and
  // every free particle of one triangle against the other (particle contacts). Both start from
  // the triangles' normals and the sides of each one's corners of the other's plane, computed
  // once here. A particle can only enter a closed surface by ending behind the face, so where no
  // corner does, as in most pairs, nothing more is computed for that direction.
  //
  // A particle belongs to several triangles, so the same (particle, triangle) comes from several
  // pairs. It is tested once, from the first triangle of the particle's incidence row that the
  // broad phase pairs with the target: every broad phase lists exactly the eligible pairs whose
  // boxes overlap, so that triangle is known locally, by a few box tests, with no sort of all
  // candidates (that was a quarter of a contact-heavy step). The pairs are tested in parallel
  // chunks whose hits are joined in chunk order, and only the few particle hits are sorted, so
  // the result is the same for any thread count.
  const BroadPhaseInput input = geometry.broadPhaseInput(boxes_, &patchFlat_);
  const auto testsFrom = [&](Index from, Index p, Index against) {
    const Box3& target = boxes_[against];
    for (Index r = topology.triangleRowStart[p]; r < topology.triangleRowStart[p + 1]; ++r) {
      const Index u = topology.triangleRefs[r];
      if (u == from) return true;  // paired with `against`: that is how we got here
      // u's surface is from's, which moves, so a pair with another surface is always eligible.
      if (overlaps(boxes_[u], target) &&
          (geometry.triangleSurface[u] != geometry.triangleSurface[against] ||
           pairEligible(input, u, against)))
        return false;
    }
    return false;
  };
  const std::size_t chunks = std::min(kPairChunks, pairs_.size());
  const std::size_t perChunk = chunks ? (pairs_.size() + chunks - 1) / chunks : 0;
  chunkHits_.reset(chunks);
  chunkEdges_.reset(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<ParticleContact>& hits = chunkHits_[chunk];
    std::vector<EdgeContact>& edges = chunkEdges_[chunk];
    ParticleContact contact;
    // The corners of `from` against `against`, whose corners at the end are `struckNow`.
    const auto testCorners = [&](Index from, Index against, const TriangleCorners& struckNow,
                                 const Vec3& struckNormal, const std::array<Scalar, 3>& endSides) {
      if (!geometry.surfaces[geometry.triangleSurface[from]].moving) return;
      const bool closed = geometry.surfaceClosed[geometry.triangleSurface[against]];
      if (closed && !(endSides[0] < 0 || endSides[1] < 0 || endSides[2] < 0)) return;
      const Triangle& struck = geometry.triangleVertices[against];
      const ParticleTarget target =
          particleTarget(geometry, motion, against, struckNow, struckNormal);
      for (int k = 0; k < 3; ++k) {
        const Index p = geometry.triangleVertices[from][k];
        if (topology.inverseMass[p] == 0 || hasVertex(struck, p)) continue;
        if (closed && !(endSides[k] < 0)) continue;  // testParticle() would find no entry
        const ParticleSides sides = particleSides(motion, p, target, endSides[k]);
        if (mayCross(motion, p, target, sides) && testsFrom(from, p, against) &&
            testParticle(geometry, motion, p, target, sides, contact))
          hits.push_back(contact);
      }
    };
    const std::size_t stop = std::min(pairs_.size(), (chunk + 1) * perChunk);
    for (std::size_t i = chunk * perChunk; i < stop; ++i) {
      const Index first = pairs_[i].first, second = pairs_[i].second;
      const TriangleCorners a = geometry.corners(motion.end, first);
      const TriangleCorners b = geometry.corners(motion.end, second);
      const Vec3 normalA = triangleNormal(a), normalB = triangleNormal(b);
      const std::array<Scalar, 3> sidesOfA = sidesOfPlane(a, b, normalB);
      const std::array<Scalar, 3> sidesOfB = sidesOfPlane(b, a, normalA);
      std::array<EdgeHit, 2> edgeHits;
      const int firstCount = intersectEdgesWithTriangle(a, normalA, b, normalB, sidesOfA, edgeHits);
      for (int k = 0; k < firstCount; ++k)
        edges.push_back({first, second, edgeHits[k].edge, edgeHits[k].hit});
      const int secondCount =
          intersectEdgesWithTriangle(b, normalB, a, normalA, sidesOfB, edgeHits);
      for (int k = 0; k < secondCount; ++k)
        edges.push_back({second, first, edgeHits[k].edge, edgeHits[k].hit});
      testCorners(first, second, b, normalB, sidesOfA);
      testCorners(second, first, a, normalA, sidesOfB);
    }
  });
  // Resting contacts drift between chunks of pairs: see ChunkBuffers::reserveLargest().
  chunkHits_.reserveLargest();
  chunkEdges_.reserveLargest();
  chunkEdges_.join(edgeContacts_);
  chunkHits_.join(particleContacts_);
  const auto byParticleTriangle = [](const ParticleContact& a, const ParticleContact& b) {
    return a.particle != b.particle ? a.particle < b.particle : a.triangle < b.triangle;
  };
  if (!setAside_.empty()) dropTangledContacts(topology, geometry, motion);
  // Each (particle, triangle) was tested from one pair only, so the hits are unique already.
  std::sort(particleContacts_.begin(), particleContacts_.end(), byParticleTriangle);
  // Hits are sorted by particle, so each particle's contacts are adjacent; within one
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
}

}  // namespace softbake
