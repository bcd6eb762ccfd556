#include "core/collision/failsafe.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <numeric>

#include "core/collision/detection.hpp"
#include "core/collision/geometry.hpp"
#include "core/collision/self_patches.hpp"
#include "core/collision/triangle_pair_intersection.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"
#include "core/union_find.hpp"

namespace softbake {

namespace {

constexpr std::size_t kChunks = 128;

/// As fractions of the skin: meetings are found within 1/100 of it and left 1/10 of it apart, well
/// above single precision's rounding at scene scale and well below what the response keeps.
constexpr double kToleranceOfSkin = 0.01;
constexpr double kSeparationOfSkin = 0.1;
/// A meeting within its tolerance at the substep's start that ends it closer by less than this
/// fraction of its separation has not closed: that much is float rounding (notClosing).
constexpr double kRoundingOfSeparation = 0.01;
/// An open body's thickness is at most this fraction of its short edges (kShortEdgeShare of them
/// are shorter): a sheet's own vertices closer than its thickness would be pushed apart in every
/// substep. A tube of 0.26 mm strips under the default 0.5 mm held the failsafe at its last stage
/// in every substep.
constexpr double kThicknessOfShortEdge = 0.25;
constexpr double kShortEdgeShare = 0.05;
/// Triangles closer than this fraction of their coordinates' magnitude touch: a few roundings of
/// single precision, in which positions are held.
constexpr double kTouchingOfExtent = 4.0 * std::numeric_limits<float>::epsilon();
/// Edges closer to parallel than this sine of their angle have no common normal to cross along.
constexpr double kParallelSine = 1e-3;

PointPath path(const CollisionGeometry& geometry, std::span<const Vec3> start,
               std::span<const Vec3> end, Index v) {
  return {geometry.vertex(start, v).cast<double>(), geometry.vertex(end, v).cast<double>()};
}

bool lessImpact(const FailsafeImpact& a, const FailsafeImpact& b) {
  return a.edge != b.edge ? a.edge < b.edge : a.vertex < b.vertex;
}

bool sameImpact(const FailsafeImpact& a, const FailsafeImpact& b) {
  return a.edge == b.edge && a.vertex == b.vertex;
}

/// The length that a share kShortEdgeShare of a body's edges are shorter than.
double shortEdge(const SceneTopology& topology, const Body& body) {
  std::vector<double> lengths;
  for (const Triangle& t : topology.bodyTriangles(body))
    for (int k = 0; k < 3; ++k)
      lengths.push_back(
          double((topology.restPosition[t[(k + 1) % 3]] - topology.restPosition[t[k]]).norm()));
  if (lengths.empty()) return 0;
  const auto at = lengths.begin() + std::ptrdiff_t(kShortEdgeShare * double(lengths.size() - 1));
  std::nth_element(lengths.begin(), at, lengths.end());
  return *at;
}

}  // namespace

double openSurfaceThickness(const SceneTopology& topology, const Body& body) {
  if (body.closed) return 0;
  return std::min(double(body.material.thickness),
                  kThicknessOfShortEdge * shortEdge(topology, body));
}

namespace {

/// The skin the tolerances are fractions of; with no skin, a ten-thousandth of the scene's size.
double failsafeSkin(const SceneTopology& topology) {
  if (topology.settings.skin > 0) return topology.settings.skin;
  Box3 bounds;
  for (const Vec3& x : topology.restPosition) bounds.extend(x);
  return bounds.isEmpty() ? 1e-3 : 1e-4 * double(bounds.diagonal().norm());
}

}  // namespace

CollisionFailsafe::CollisionFailsafe(const SceneTopology& topology,
                                     const CollisionGeometry& geometry, FailsafePasses passes)
    : passes_(passes),
      tolerance_(kToleranceOfSkin * failsafeSkin(topology)),
      separation_(kSeparationOfSkin * failsafeSkin(topology)),
      broadPhase_(makeBroadPhase(BroadPhaseKind::Bvh)) {
  thickness_.assign(geometry.surfaces.size(), 0.0);
  margin_ = tolerance_;
  for (std::size_t b = 0; b < topology.bodies.size(); ++b)
    if (!topology.bodies[b].closed) {
      thickness_[b] = openSurfaceThickness(topology, topology.bodies[b]);
      margin_ = std::max(margin_, thickness_[b]);
    }
  const std::size_t triangles = geometry.triangleVertices.size();
  const std::size_t vertices = geometry.particleCount + geometry.staticVertex.size();
  // Ownership: the lowest-numbered triangle holding each vertex and each edge.
  std::vector<Index> vertexOwner(vertices, ~Index(0));
  std::vector<std::pair<std::pair<Index, Index>, Index>> edges;
  edges.reserve(3 * triangles);
  for (Index t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index a = geometry.triangleVertices[t][k],
                  b = geometry.triangleVertices[t][(k + 1) % 3];
      vertexOwner[a] = std::min(vertexOwner[a], t);
      edges.push_back({{std::min(a, b), std::max(a, b)}, t});
    }
  std::sort(edges.begin(), edges.end());
  owns_.assign(triangles, 0);
  for (Index t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k)
      if (vertexOwner[geometry.triangleVertices[t][k]] == t) owns_[t] |= std::uint8_t(1u << k);
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (i > 0 && edges[i].first == edges[i - 1].first) continue;  // sorted: the first is the lowest
    const Index t = edges[i].second;
    const Triangle& corners = geometry.triangleVertices[t];
    for (int k = 0; k < 3; ++k) {
      const Index a = corners[k], b = corners[(k + 1) % 3];
      if (std::pair(std::min(a, b), std::max(a, b)) == edges[i].first)
        owns_[t] |= std::uint8_t(1u << (3 + k));
    }
  }
  moved_.assign(geometry.particleCount, 0);
  onPlane_.assign(geometry.particleCount, 0);
  inZone_.assign(geometry.particleCount, 0);
  bodyBack_.assign(topology.bodies.size(), kBodyFree);
  bodyGroupSize_.assign(topology.bodies.size(), 0);
  groupBodies_.assign(topology.bodies.size(), 0);
  groupMeets_.assign(topology.bodies.size(), 0);
  groupRests_.assign(topology.bodies.size(), 0);
  groupNew_.assign(topology.bodies.size(), 0);
  groupMass_.assign(topology.bodies.size(), 0);
  groupLowest_.assign(topology.bodies.size(), 0);
  groupShift_.assign(topology.bodies.size(), Vec3d::Zero());
  groupMomentum_.assign(topology.bodies.size(), Vec3d::Zero());
  bodyRoot_.resize(topology.bodies.size());
  zoneParent_.resize(geometry.particleCount);
  std::iota(zoneParent_.begin(), zoneParent_.end(), Index(0));
  zoneFixed_.assign(geometry.particleCount, 0);
  gravityTaken_.assign(geometry.particleCount, 0);
  zoneMass_.assign(geometry.particleCount, 0);
  zoneShift_.assign(geometry.particleCount, Vec3d::Zero());
  zoneVelocity_.assign(geometry.particleCount, Vec3d::Zero());
}

void CollisionFailsafe::leaveTangled(const InitialOverlaps& overlaps) {
  tangled_ = overlappingSurfaces(overlaps);
}

void CollisionFailsafe::leaveOverlapping(const InitialOverlaps& overlaps) {
  overlapping_ = overlappingSurfaces(overlaps);
}

bool CollisionFailsafe::betweenOverlapping(const CollisionGeometry& geometry,
                                           const FailsafeImpact& impact) const {
  // Every triangle around a collision vertex lies on the vertex's surface.
  const auto surface = [&](Index v) {
    return geometry.triangleSurface[geometry.trianglesAround(v).front()];
  };
  const Index first = surface(impact.vertex[0]);
  const Index second =
      impact.edge ? surface(impact.vertex[2]) : geometry.triangleSurface[impact.face];
  return holdsSurfacePair(overlapping_, first, second);
}

FailsafeStats CollisionFailsafe::apply(const SceneTopology& topology,
                                       const CollisionGeometry& geometry,
                                       CollisionDetector& detector, std::span<const Vec3> start,
                                       SimulationState& state, double dt) {
  FailsafeStats stats;
  std::fill(moved_.begin(), moved_.end(), 0);
  std::fill(onPlane_.begin(), onPlane_.end(), 0);
  const int passes = passes_.impulses + passes_.zones;
  // Each pass of stage 3 moves at least one more body as one, joins two groups or puts one to rest
  // (one at its start meets nothing also at its start), so it ends within three times the body
  // count; the global return past it is never expected.
  const int lastResort = passes + 3 * int(topology.bodies.size());
  for (int pass = 0; pass <= lastResort; ++pass) {
    ++stats.passes;
    const bool found = findImpacts(topology, geometry, detector, start, state.position, pass > 0);
    std::fill(moved_.begin(), moved_.end(), 0);
    if (!found) break;
    stats.impacts += impacts_.size() + crossings_.size();
    // Crossings only zones part: passes of impulses would leave them as they are.
    if (pass < passes_.impulses && impacts_.empty()) pass = passes_.impulses;
    if (pass == lastResort) {
      // The start had no crossings, so going back to it has none.
      std::copy(start.begin(), start.begin() + Index(state.position.size()),
                state.position.begin());
      std::fill(state.velocity.begin(), state.velocity.end(), Vec3::Zero());
      stats.frozen += pass == passes;
      stats.frozenBodies += topology.bodies.size();
    } else if (pass >= passes) {
      // Stage 3: the bodies of what still meets go back to where they started, and move from
      // there as one (putBodiesBack). The whole scene put back at rest in one go stopped every
      // body dead for a meeting of two, and an assembly put back at rest stopped in mid-air.
      if (pass == passes) {
        ++stats.frozen;
        joinFittedBodies(topology, geometry, detector);
      }
      putBodiesBack(topology, geometry, start, state, stats);
    } else if (pass < passes_.impulses) {
      applyImpulses(topology, geometry, state);
      // Measured again next pass, with the meetings the impulses moved.
      for (const TrianglePair& crossing : crossings_)
        for (Index t : {crossing.first, crossing.second})
          for (Index v : geometry.triangleVertices[t])
            if (v < geometry.particleCount) moved_[v] = 1;
    } else {
      // A translating pass that finds the very meetings of the pass before cannot part them:
      // translated again, the zones end where they ended, and an engine resting on the ground
      // ran its 60 translating passes over the same 4 meetings in every substep (228 s a frame).
      // Those zones go to the passes that leave a zone where it started.
      const int firstStaying = passes_.impulses + passes_.translatingZones;
      if (pass < firstStaying && pass > passes_.impulses && sameMeetings()) pass = firstStaying;
      stats.zoneParticles =
          moveZones(topology, geometry, start, state, pass >= firstStaying ? dt : 0.0);
      lastMeetings_.clear();
      for (const FailsafeImpact& impact : impacts_) lastMeetings_.push_back(impact.vertex);
      lastCrossings_ = crossings_;
    }
    keepAbovePlanes(topology, state, dt);
  }
  clearZones();
  if (stats.frozen) std::fill(bodyBack_.begin(), bodyBack_.end(), kBodyFree);
  return stats;
}

bool CollisionFailsafe::findImpacts(const SceneTopology& topology,
                                    const CollisionGeometry& geometry, CollisionDetector& detector,
                                    std::span<const Vec3> start, std::span<const Vec3> end,
                                    bool onlyMoved) {
  // The box of each vertex's path, grown by the tolerance: the triangles' boxes are made of them,
  // and most primitives of a candidate pair are rejected by these before any cubic is formed.
  updateCollisionBoxes(topology, geometry, {start, end}, boxes_, Scalar(margin_), pathBoxes_);
  // The detector's cached pairs hold this stage's almost always: the response moves particles
  // far less than the cache's margin, and the few triangles it moves out are found again there.
  // Its own broad phase only when the detector keeps no cache.
  // A later pass measures again only the pairs of triangles the previous pass moved; of an
  // engine's 1.5M pairs a pass moves a few hundred triangles.
  const Index particles = geometry.particleCount;
  std::span<const std::uint8_t> involving;
  if (onlyMoved) {
    triangleMoved_.resize(geometry.triangleVertices.size());
    for (std::size_t t = 0; t < triangleMoved_.size(); ++t) {
      std::uint8_t any = 0;
      for (Index v : geometry.triangleVertices[t]) any |= std::uint8_t(v < particles && moved_[v]);
      triangleMoved_[t] = any;
    }
    involving = triangleMoved_;
  }
  // Self-collision culled by normal cones, as the detector culls it, but over this pass's own
  // motion: impulses and zones turn triangles, and a patch the detector found flat may no longer
  // be one (a zone shifted in a body's fold let two of its triangles cross, unseen).
  updateFlatPatches(geometry, start, end, patchFlat_);
  const BroadPhaseInput input = geometry.broadPhaseInput(boxes_, &patchFlat_);
  if (!detector.findCachedPairs(input, pairs_, involving))
    pairCache_.findPairs(*broadPhase_, input, pairs_, involving);
  detector.dropIgnoredPairs(geometry, pairs_);
  dropSurfacePairs(geometry, tangled_, pairs_);
  // Static vertices stand still: their path is a point.
  pathBoxes_.resize(particles + geometry.staticVertex.size());
  const Scalar grow = Scalar(margin_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(particles, pathBoxes_.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t v = range.begin(); v != range.end(); ++v) {
                        const Vec3 point = geometry.vertex(start, Index(v));
                        pathBoxes_[v] =
                            Box3(Vec3(point.array() - grow), Vec3(point.array() + grow));
                      }
                    });
  const auto pathBox = [&](Index v) -> const Box3& { return pathBoxes_[v]; };
  const std::size_t chunks = std::min(kChunks, pairs_.size());
  const std::size_t perChunk = chunks ? (pairs_.size() + chunks - 1) / chunks : 0;
  chunkImpacts_.reset(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<FailsafeImpact>& found = chunkImpacts_[chunk];
    const std::size_t stop = std::min(pairs_.size(), (chunk + 1) * perChunk);
    for (std::size_t i = chunk * perChunk; i < stop; ++i) {
      const Index first = pairs_[i].first, second = pairs_[i].second;
      // Within one surface the triangles around a vertex may not all pair (neighbours of the
      // other triangle are not eligible), so there every primitive is tested and duplicates go.
      const Index firstSurface = geometry.triangleSurface[first];
      const Index secondSurface = geometry.triangleSurface[second];
      const bool everyPrimitive = firstSurface == secondSurface;
      const double thickness = std::max(thickness_[firstSurface], thickness_[secondSurface]);
      const double tolerance = std::max(tolerance_, thickness);
      const double separation = std::max(separation_, thickness);
      const double friction = std::sqrt(double(geometry.friction[firstSurface]) *
                                        double(geometry.friction[secondSurface]));
      const auto vertexFace = [&](Index from, Index face) {
        const Triangle& f = geometry.triangleVertices[face];
        for (int k = 0; k < 3; ++k) {
          const Index p = geometry.triangleVertices[from][k];
          if ((!everyPrimitive && !(owns_[from] & (1u << k))) || hasVertex(f, p)) continue;
          if (p >= particles && f[0] >= particles) continue;  // static against static
          if (!overlaps(pathBox(p), boxes_[face])) continue;
          const std::optional<Impact> impact = vertexFaceImpact(
              path(geometry, start, end, p), path(geometry, start, end, f[0]),
              path(geometry, start, end, f[1]), path(geometry, start, end, f[2]), tolerance);
          if (impact)
            found.push_back({{p, f[0], f[1], f[2]}, face, false, separation, friction, *impact});
        }
      };
      vertexFace(first, second);
      vertexFace(second, first);
      const Triangle& a = geometry.triangleVertices[first];
      const Triangle& b = geometry.triangleVertices[second];
      // The edges each side tests, and their path boxes, each already against the other
      // triangle's box.
      const auto testedEdges = [&](Index t, const Triangle& corners, Index other,
                                   std::array<Box3, 3>& box) {
        unsigned mask = everyPrimitive ? 7u : unsigned(owns_[t] >> 3);
        for (int k = 0; k < 3; ++k) {
          if (!(mask & (1u << k))) continue;
          box[k] = pathBox(corners[k]);
          box[k].extend(pathBox(corners[(k + 1) % 3]));
          if (!overlaps(box[k], boxes_[other])) mask &= ~(1u << k);
        }
        return mask;
      };
      std::array<Box3, 3> boxA, boxB;
      const unsigned edgesA = testedEdges(first, a, second, boxA);
      const unsigned edgesB = edgesA ? testedEdges(second, b, first, boxB) : 0u;
      for (int j = 0; edgesB && j < 3; ++j) {
        if (!(edgesA & (1u << j))) continue;
        // Each edge's ends in increasing order, and the edges in order of their first end: a
        // meeting found from two pairs is then the same computation, bit for bit.
        const Index p0 = std::min(a[j], a[(j + 1) % 3]), p1 = std::max(a[j], a[(j + 1) % 3]);
        for (int k = 0; k < 3; ++k) {
          if (!(edgesB & (1u << k)) || !overlaps(boxA[j], boxB[k])) continue;
          const Index q0 = std::min(b[k], b[(k + 1) % 3]), q1 = std::max(b[k], b[(k + 1) % 3]);
          if (p0 == q0 || p0 == q1 || p1 == q0 || p1 == q1) continue;
          std::array<Index, 4> v =
              p0 < q0 ? std::array{p0, p1, q0, q1} : std::array{q0, q1, p0, p1};
          const std::optional<Impact> impact = edgeEdgeImpact(
              path(geometry, start, end, v[0]), path(geometry, start, end, v[1]),
              path(geometry, start, end, v[2]), path(geometry, start, end, v[3]), tolerance);
          if (impact) found.push_back({v, 0, true, separation, friction, *impact});
        }
      }
    }
  });
  chunkImpacts_.join(impacts_);
  std::sort(impacts_.begin(), impacts_.end(), lessImpact);
  impacts_.erase(std::unique(impacts_.begin(), impacts_.end(), sameImpact), impacts_.end());
  // Each meeting's verdict, in parallel (the intersection tests dominate an assembly's pass),
  // then the kept ones in order. The rules, and why each holds, are in the header. A fitted
  // meeting gives, unless its triangles come to touch. One that does not close is dropped, unless
  // its triangles end crossing where they did not, between surfaces apart at the scene's start.
  // One whose triangles crossed already at the substep's start is dropped if it is fitted or its
  // surfaces overlapped at the scene's start. The exceptions' triangles are zoned whole
  // (kCrossing), never pushed.
  enum Verdict : std::uint8_t { kKeep, kDrop, kCrossing };
  verdicts_.resize(impacts_.size());
  crossingOf_.resize(impacts_.size());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, impacts_.size(), 16),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const FailsafeImpact& impact = impacts_[i];
          // Triangles of the meeting that intersect at the end and did not at the start.
          const auto newlyCrossing = [&](Contact contact) -> std::optional<TrianglePair> {
            const std::optional<TrianglePair> now =
                crossingTriangles(geometry, end, impact, contact);
            if (now && !crossingTriangles(geometry, start, impact, contact)) return now;
            return std::nullopt;
          };
          const auto zoneOrDrop = [&](const std::optional<TrianglePair>& crossing) {
            if (!crossing) return kDrop;
            crossingOf_[i] = *crossing;
            return kCrossing;
          };
          Verdict verdict = kKeep;
          const bool fitted = closeAtRest(topology, geometry, impact);
          if (fitted && !crosses(geometry, start, end, impact, impact.separation)) {
            verdict = zoneOrDrop(newlyCrossing(Contact::Touching));
          } else if (notClosing(geometry, start, end, impact)) {
            verdict = betweenOverlapping(geometry, impact)
                          ? kDrop
                          : zoneOrDrop(newlyCrossing(Contact::Crossing));
          } else if (const std::optional<TrianglePair> before =
                         crossingTriangles(geometry, start, impact, Contact::Crossing)) {
            verdict = fitted || betweenOverlapping(geometry, impact) ? kDrop : zoneOrDrop(before);
          }
          verdicts_[i] = verdict;
        }
      });
  crossings_.clear();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < impacts_.size(); ++i) {
    if (verdicts_[i] == kCrossing) crossings_.push_back(crossingOf_[i]);
    if (verdicts_[i] == kKeep) impacts_[kept++] = impacts_[i];
  }
  impacts_.resize(kept);
  std::sort(crossings_.begin(), crossings_.end());
  crossings_.erase(std::unique(crossings_.begin(), crossings_.end()), crossings_.end());
  return !impacts_.empty() || !crossings_.empty();
}

bool CollisionFailsafe::closeAtRest(const SceneTopology& topology,
                                    const CollisionGeometry& geometry,
                                    const FailsafeImpact& impact) const {
  std::array<Vec3d, 4> rest;
  for (int k = 0; k < 4; ++k)
    rest[k] = geometry.vertex(topology.restPosition, impact.vertex[k]).cast<double>();
  const double distance = impact.edge ? segmentDistance(rest[0], rest[1], rest[2], rest[3])
                                      : pointTriangleDistance(rest[0], rest[1], rest[2], rest[3]);
  return distance < impact.separation;
}

bool CollisionFailsafe::crosses(const CollisionGeometry& geometry, std::span<const Vec3> start,
                                std::span<const Vec3> end, const FailsafeImpact& impact,
                                double tolerance) {
  // The signed distance of the first primitive from the second, at the start and at the end:
  // along the face's normal, or along the two edges' common normal. Parallel edges have no
  // common normal, hence no sides (the vertex–face tests see such edges pass), and so do
  // parallel edges fitted into each other, which is what most CAD fits are.
  const auto side = [&](std::span<const Vec3> at) {
    std::array<Vec3d, 4> x;
    for (int k = 0; k < 4; ++k) x[k] = geometry.vertex(at, impact.vertex[k]).cast<double>();
    if (!impact.edge) {
      const Vec3d normal = (x[2] - x[1]).cross(x[3] - x[1]);
      const double area = normal.norm();
      return area > 0 ? (x[0] - x[1]).dot(normal) / area : 0.0;
    }
    const Vec3d across = (x[1] - x[0]).cross(x[3] - x[2]);
    const double sine = across.norm();
    if (!(sine > kParallelSine * (x[1] - x[0]).norm() * (x[3] - x[2]).norm())) return 0.0;
    const std::array<double, 2> s = closestSegmentParameters(x[0], x[1], x[2], x[3]);
    const Vec3d between = (x[0] + s[0] * (x[1] - x[0])) - (x[2] + s[1] * (x[3] - x[2]));
    return between.dot(across) / sine;
  };
  // Ending on the other side by less than the tolerance is rounding, not a crossing: two faces
  // fitted onto each other swap sides by it in every substep.
  const double before = side(start), after = side(end);
  return (before > 0 && after < -tolerance) || (before < 0 && after > tolerance);
}

bool CollisionFailsafe::notClosing(const CollisionGeometry& geometry, std::span<const Vec3> start,
                                   std::span<const Vec3> end, const FailsafeImpact& impact) {
  const auto gap = [&](std::span<const Vec3> at) {
    double sum = 0;
    for (int k = 0; k < 4; ++k)
      sum += impact.impact.weight[k] *
             impact.impact.normal.dot(geometry.vertex(at, impact.vertex[k]).cast<double>());
    return sum;
  };
  // No closer by less than a hundredth of the separation is rounding: a zone translated as one
  // (stage 2) keeps its primitives where they were relative to each other only to float
  // precision, and taking that for closing met the zone with itself in every pass, until it was
  // left at the substep's start without its velocity: a falling assembly of fitted parts lost
  // momentum at every such substep and hung in the air. So does a group of bodies moved as one
  // (stage 3), where the rounding takes two primitives a hair past their tolerance within the
  // substep: one such meeting put assimp's engine, moved as one, back at rest above the ground.
  const double before = gap(start), after = gap(end);
  return (before > 0) == (after > 0) &&
         std::abs(after) >= std::abs(before) - kRoundingOfSeparation * impact.separation;
}

std::optional<TrianglePair> CollisionFailsafe::crossingTriangles(const CollisionGeometry& geometry,
                                                                 std::span<const Vec3> at,
                                                                 const FailsafeImpact& impact,
                                                                 Contact contact) const {
  const auto around = [&](Index v) { return geometry.trianglesAround(v); };
  TrianglePairHits hits;
  // Touching counts: faces of two surfaces pressed onto one plane (stacked near-copies lifted
  // to the same height above the ground) overlap there, which the line–triangle test, blind to
  // coplanar triangles, does not report.
  const auto intersect = [&](Index t, Index u) {
    if (geometry.trianglesCross(at, t, u, hits)) return true;
    if (contact == Contact::Crossing) return false;
    // Triangles that share a corner touch there by construction.
    if (geometry.shareVertex(t, u)) return false;
    const TriangleCorners first = geometry.corners(at, t), second = geometry.corners(at, u);
    std::array<Vec3d, 3> a, b;
    double extent = 0;
    for (int k = 0; k < 3; ++k) {
      a[k] = first[k].cast<double>();
      b[k] = second[k].cast<double>();
      extent = std::max({extent, a[k].cwiseAbs().maxCoeff(), b[k].cwiseAbs().maxCoeff()});
    }
    return triangleDistance(a, b) <= kTouchingOfExtent * extent;
  };
  const auto pair = [](Index t, Index u) { return TrianglePair{std::min(t, u), std::max(t, u)}; };
  if (!impact.edge) {
    for (Index t : around(impact.vertex[0]))
      if (intersect(t, impact.face)) return pair(t, impact.face);
    return std::nullopt;
  }
  for (Index t : around(impact.vertex[0])) {
    if (!hasVertex(geometry.triangleVertices[t], impact.vertex[1])) continue;
    for (Index u : around(impact.vertex[2]))
      if (hasVertex(geometry.triangleVertices[u], impact.vertex[3]) && intersect(t, u))
        return pair(t, u);
  }
  return std::nullopt;
}

void CollisionFailsafe::applyImpulses(const SceneTopology& topology,
                                      const CollisionGeometry& geometry, SimulationState& state) {
  const Index particles = geometry.particleCount;
  for (const FailsafeImpact& meeting : impacts_) {
    const Vec3d& normal = meeting.impact.normal;
    double gap = 0, resistance = 0;
    Vec3d relative = Vec3d::Zero();  // the first primitive's velocity relative to the second's
    std::array<double, 4> inverseMass{};
    for (int i = 0; i < 4; ++i) {
      const Index v = meeting.vertex[i];
      const double w = meeting.impact.weight[i];
      gap += w * normal.dot(geometry.vertex(state.position, v).cast<double>());
      if (v < particles) relative += w * state.velocity[v].cast<double>();
      inverseMass[i] = v < particles ? double(topology.inverseMass[v]) : 0.0;
      resistance += w * w * inverseMass[i];
    }
    const double speed = normal.dot(relative);
    for (Index v : meeting.vertex)
      if (v < particles) moved_[v] = 1;  // measured again next pass, resolved or not
    if (gap >= meeting.separation || resistance <= 0) continue;
    // The primitives end `separation` apart, and their velocities lose what approach they had
    // along the normal, no more: an inelastic impulse (Bridson et al. §7.1). Setting the
    // velocities to the push over the substep instead made every push a kick, however little
    // the primitives had approached: two parts fitted closer than the separation, a light corner
    // against a heavy part, flew apart at metres a second and kicked the next part.
    const double impulse = (meeting.separation - gap) / resistance;
    const double stop = std::max(0.0, -speed) / resistance;
    // Coulomb friction with the same impulse (§7.2): the tangential speed loses at most the
    // friction coefficient times the normal speed taken. Without it, faces fitted onto each other,
    // which only this stage holds, slid off one another at the lightest sideways push.
    const Vec3d tangential = relative - speed * normal;
    const double slide = tangential.norm();
    const double slow = slide > 0 ? std::min(slide, meeting.friction * stop * resistance) : 0.0;
    const Vec3d brake = slow > 0 ? Vec3d(-(slow / resistance / slide) * tangential) : Vec3d::Zero();
    for (int i = 0; i < 4; ++i) {
      if (inverseMass[i] == 0) continue;
      const double share = inverseMass[i] * meeting.impact.weight[i];
      const Index v = meeting.vertex[i];
      state.position[v] += (impulse * share * normal).cast<Scalar>();
      state.velocity[v] += (share * (stop * normal + brake)).cast<Scalar>();
    }
  }
}

void CollisionFailsafe::keepAbovePlanes(const SceneTopology& topology, SimulationState& state,
                                        double dt) {
  for (Index v = 0; v < Index(moved_.size()); ++v) {
    if (!moved_[v]) continue;
    for (const PlaneCollider& plane : topology.planes) {
      const double height =
          plane.normal.cast<double>().dot((state.position[v] - plane.point).cast<double>());
      if (height >= 0) continue;
      const Vec3d lift = (separation_ - height) * plane.normal.cast<double>();
      state.position[v] += lift.cast<Scalar>();
      state.velocity[v] += (lift / dt).cast<Scalar>();
      onPlane_[v] = 1;
    }
  }
}

Index CollisionFailsafe::zoneOf(Index v) {
  return findRoot(zoneParent_, v);
}

template <class Visit>
void CollisionFailsafe::forEachMeeting(const CollisionGeometry& geometry, Visit&& visit) const {
  for (const FailsafeImpact& meeting : impacts_) visit(std::span<const Index>(meeting.vertex));
  for (const TrianglePair& crossing : crossings_) {
    const Triangle& a = geometry.triangleVertices[crossing.first];
    const Triangle& b = geometry.triangleVertices[crossing.second];
    const std::array<Index, 6> corners{a[0], a[1], a[2], b[0], b[1], b[2]};
    visit(std::span<const Index>(corners));
  }
}

std::size_t CollisionFailsafe::moveZones(const SceneTopology& topology,
                                         const CollisionGeometry& geometry,
                                         std::span<const Vec3> start, SimulationState& state,
                                         double stayFor) {
  const bool stayAtStart = stayFor > 0;
  const Index particles = geometry.particleCount;
  const auto join = [&](Index v) {
    if (!inZone_[v]) {
      inZone_[v] = 1;
      zoneMembers_.push_back(v);
    }
  };
  const auto unite = [&](std::span<const Index> vertices) {
    Index root = ~Index(0);
    bool fixed = false;
    for (Index v : vertices) {
      if (v >= particles) {
        fixed = true;
        continue;
      }
      join(v);
      fixed = fixed || topology.inverseMass[v] == 0;
      const Index r = zoneOf(v);
      if (root == ~Index(0)) {
        root = r;
      } else if (r != root) {
        // The lower index becomes the root, so zones do not depend on the order of meetings.
        const Index high = std::max(r, root);
        root = joinRoots(zoneParent_, r, root);
        zoneFixed_[root] = zoneFixed_[root] || zoneFixed_[high];
      }
    }
    if (root != ~Index(0) && fixed) zoneFixed_[root] = 1;
  };
  forEachMeeting(geometry, unite);
  for (Index v : zoneMembers_) {
    const Index root = zoneOf(v);
    if (onPlane_[v]) zoneFixed_[root] = 1;
    zoneMass_[root] = 0;
    zoneShift_[root].setZero();
    zoneVelocity_[root].setZero();
  }
  for (Index v : zoneMembers_) {
    const Index root = zoneOf(v);
    const double m = topology.mass[v];
    zoneMass_[root] += m;
    zoneShift_[root] += m * (state.position[v] - start[v]).cast<double>();
    // A particle a staying zone placed before has had the gravity taken once already.
    Vec3d velocity = state.velocity[v].cast<double>();
    if (gravityTaken_[v]) velocity += stayFor * topology.settings.gravity.cast<double>();
    zoneVelocity_[root] += m * velocity;
  }
  for (Index v : zoneMembers_) {
    const Index root = zoneOf(v);
    moved_[v] = 1;
    if (zoneFixed_[root] || zoneMass_[root] <= 0) {
      state.position[v] = start[v];
      state.velocity[v].setZero();
    } else if (stayAtStart) {
      // Where it started, with the momentum it had there: its momentum now less the substep's
      // gravity, since what acts within a zone adds none. Left at rest, a falling assembly's
      // zones stopped it in mid-air; with the gravity kept, each such substep gained energy.
      state.position[v] = start[v];
      state.velocity[v] = (zoneVelocity_[root] / zoneMass_[root] -
                           stayFor * topology.settings.gravity.cast<double>())
                              .cast<Scalar>();
      gravityTaken_[v] = 1;
    } else {
      state.position[v] = start[v] + (zoneShift_[root] / zoneMass_[root]).cast<Scalar>();
      state.velocity[v] = (zoneVelocity_[root] / zoneMass_[root]).cast<Scalar>();
    }
  }
  return zoneMembers_.size();
}

void CollisionFailsafe::joinFittedBodies(const SceneTopology& topology,
                                         const CollisionGeometry& geometry,
                                         const CollisionDetector& detector) {
  const auto bodyOf = [&](Index triangle) {
    const Index v = geometry.triangleVertices[triangle][0];
    return v < geometry.particleCount ? topology.particleBody[v] : ~Index(0);
  };
  // An assembly goes back whole: parts fitted onto each other that were left a substep apart
  // would start their next one a substep's travel out of their fits.
  std::iota(bodyRoot_.begin(), bodyRoot_.end(), Index(0));
  for (const TrianglePair& pair : detector.fittedPairs()) {
    const Index a = bodyOf(pair.first), b = bodyOf(pair.second);
    if (a != ~Index(0) && b != ~Index(0))
      joinRoots(bodyRoot_, findRoot(bodyRoot_, a), findRoot(bodyRoot_, b));
  }
}

void CollisionFailsafe::putBodiesBack(const SceneTopology& topology,
                                      const CollisionGeometry& geometry,
                                      std::span<const Vec3> start, SimulationState& state,
                                      FailsafeStats& stats) {
  const Index particles = geometry.particleCount;
  const auto groupOf = [&](Index body) { return findRoot(bodyRoot_, body); };
  // The bodies of one meeting go together: moved as one, they cannot meet each other.
  forEachMeeting(geometry, [&](std::span<const Index> vertices) {
    Index group = ~Index(0);
    for (Index v : vertices) {
      if (v >= particles) continue;
      const Index g = groupOf(topology.particleBody[v]);
      group = group == ~Index(0) ? g : joinRoots(bodyRoot_, group, g);
    }
  });
  forEachMeeting(geometry, [&](std::span<const Index> vertices) {
    Index group = ~Index(0);
    bool fixed = false;
    for (Index v : vertices) {
      if (v >= particles)
        fixed = true;
      else
        group = groupOf(topology.particleBody[v]);
    }
    if (group == ~Index(0)) return;
    groupMeets_[group] = 1;
    if (fixed) groupRests_[group] = 1;  // against a static mesh: moving it as one cannot help
  });
  // A group goes back at rest where it met what cannot move (a static mesh, a pin), where it holds
  // a body already back at rest, and where it met again as it was: no body new to it, and no two
  // groups that moved apart joined in it. Every other group moves as one from its start, with its
  // mean displacement and velocity: a rigid impact zone of whole bodies (Bridson et al.'s also
  // turn; these only translate), so an assembly that meets itself in free fall keeps falling.
  // Two groups that each moved as one and then met move on as one: at rest, assimp's engine
  // (its assembly slowed by the ground, a part of it still falling) stopped dead above the
  // ground. Each pass so moves a body, joins two groups or puts one to rest, and the stage ends
  // within three times the body count.
  for (std::size_t b = 0; b < bodyBack_.size(); ++b) {
    const Index g = groupOf(Index(b));
    if (!groupMeets_[g]) continue;
    if (bodyBack_[b] == kBodyAtRest) groupRests_[g] = 1;
    ++groupBodies_[g];
    const Body& body = topology.bodies[b];
    for (Index p = body.firstParticle; p < body.firstParticle + body.particleCount; ++p) {
      if (topology.inverseMass[p] == 0) groupRests_[g] = 1;
      const double m = topology.mass[p];
      groupMass_[g] += m;
      groupShift_[g] += m * (state.position[p] - start[p]).cast<double>();
      groupMomentum_[g] += m * state.velocity[p].cast<double>();
    }
  }
  for (std::size_t b = 0; b < bodyBack_.size(); ++b) {
    const Index g = groupOf(Index(b));
    if (groupMeets_[g] && (bodyBack_[b] == kBodyFree || bodyGroupSize_[b] < groupBodies_[g]))
      groupNew_[g] = 1;
  }
  const auto rests = [&](Index g) {
    return groupRests_[g] || !groupNew_[g] || !(groupMass_[g] > 0);
  };
  for (std::size_t g = 0; g < bodyBack_.size(); ++g)
    if (groupMeets_[g] && !rests(Index(g))) {
      groupShift_[g] /= groupMass_[g];
      groupMomentum_[g] /= groupMass_[g];
    }
  // A group that reaches a plane lands on it as one: lifted along the plane's normal until none of
  // it is below the plane, as keepAbovePlanes() lifts a particle, and without its speed into the
  // plane. Put back at rest where its substep started, as against what cannot move, an assembly
  // that reached the ground within the substep stopped above it, and fell again.
  for (const PlaneCollider& plane : topology.planes) {
    const Vec3d normal = plane.normal.cast<double>();
    std::fill(groupLowest_.begin(), groupLowest_.end(), 0.0);
    for (std::size_t b = 0; b < bodyBack_.size(); ++b) {
      const Index g = groupOf(Index(b));
      if (!groupMeets_[g] || rests(g)) continue;
      const Body& body = topology.bodies[b];
      for (Index p = body.firstParticle; p < body.firstParticle + body.particleCount; ++p)
        groupLowest_[g] = std::min(
            groupLowest_[g], heightAbove(plane, Vec3d(start[p].cast<double>() + groupShift_[g])));
    }
    for (std::size_t g = 0; g < bodyBack_.size(); ++g) {
      if (!(groupLowest_[g] < 0)) continue;
      groupShift_[g] += (separation_ - groupLowest_[g]) * normal;
      groupMomentum_[g] -= std::min(0.0, normal.dot(groupMomentum_[g])) * normal;
    }
  }
  for (std::size_t b = 0; b < bodyBack_.size(); ++b) {
    const Index g = groupOf(Index(b));
    if (!groupMeets_[g]) continue;
    const bool rest = rests(g);
    const Vec3 shift = rest ? Vec3::Zero() : Vec3(groupShift_[g].cast<Scalar>());
    const Vec3 velocity = rest ? Vec3::Zero() : Vec3(groupMomentum_[g].cast<Scalar>());
    if (rest && bodyBack_[b] != kBodyAtRest) ++stats.frozenBodies;
    if (!rest && bodyBack_[b] == kBodyFree) ++stats.bodiesMovedAsOne;
    bodyBack_[b] = rest ? kBodyAtRest : kBodyMovedAsOne;
    bodyGroupSize_[b] = groupBodies_[g];
    const Body& body = topology.bodies[b];
    for (Index p = body.firstParticle; p < body.firstParticle + body.particleCount; ++p) {
      state.position[p] = start[p] + shift;
      state.velocity[p] = velocity;
      moved_[p] = 1;
    }
  }
  for (std::size_t b = 0; b < bodyBack_.size(); ++b) {
    groupMeets_[b] = groupRests_[b] = groupNew_[b] = 0;
    groupBodies_[b] = 0;
    groupMass_[b] = 0;
    groupShift_[b].setZero();
    groupMomentum_[b].setZero();
  }
}

bool CollisionFailsafe::sameMeetings() const {
  return crossings_ == lastCrossings_ &&
         std::equal(impacts_.begin(), impacts_.end(), lastMeetings_.begin(), lastMeetings_.end(),
                    [](const FailsafeImpact& impact, const std::array<Index, 4>& vertices) {
                      return impact.vertex == vertices;
                    });
}

void CollisionFailsafe::clearZones() {
  for (Index v : zoneMembers_) {
    zoneParent_[v] = v;
    zoneFixed_[v] = 0;
    inZone_[v] = 0;
    gravityTaken_[v] = 0;
  }
  zoneMembers_.clear();
}

}  // namespace softbake
