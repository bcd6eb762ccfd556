#include "core/collision/initial_overlap.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <map>

#include "core/collision/continuous_collision.hpp"
#include "core/collision/geometry.hpp"
#include "core/collision/triangle_pair_intersection.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

namespace {
/// The pairs of `from` for which `keep(pair, hits)` holds, in order, into `out`: tested in
/// parallel, each range with its own scratch hits, then gathered in order.
template <typename Keep>
void keepPairs(std::span<const TrianglePair> from, std::vector<TrianglePair>& out, Keep keep) {
  std::vector<char> kept(from.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, from.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      TrianglePairHits hits;
                      for (std::size_t k = range.begin(); k != range.end(); ++k)
                        kept[k] = keep(from[k], hits);
                    });
  out.clear();
  for (std::size_t k = 0; k < from.size(); ++k)
    if (kept[k]) out.push_back(from[k]);
}
}  // namespace

std::vector<std::pair<Index, Index>> overlappingSurfaces(const InitialOverlaps& overlaps) {
  std::vector<std::pair<Index, Index>> surfaces;
  surfaces.reserve(overlaps.bySurfaces.size());
  for (const SurfaceOverlap& overlap : overlaps.bySurfaces)
    surfaces.emplace_back(overlap.firstSurface, overlap.secondSurface);
  return surfaces;
}

InitialOverlaps findInitialOverlaps(const SceneTopology& topology,
                                    const CollisionGeometry& geometry,
                                    std::span<const Vec3> positions, Scalar closeDistance) {
  InitialOverlaps overlaps;
  if (geometry.triangleVertices.empty()) return overlaps;
  // Boxes of a substep that does not move: each triangle's box around its corners.
  std::vector<Box3> boxes;
  updateCollisionBoxes(topology, geometry, {positions, positions}, boxes,
                       std::max(topology.settings.skin, closeDistance));
  std::vector<CollisionSurface> allSelfColliding = geometry.surfaces;
  for (CollisionSurface& surface : allSelfColliding) surface.selfCollision = surface.moving;
  BroadPhaseInput input = geometry.broadPhaseInput(boxes);
  input.surfaces = allSelfColliding;
  std::vector<TrianglePair> candidates;
  makeBroadPhase(BroadPhaseKind::Bvh)->findPairs(input, candidates);

  std::sort(candidates.begin(), candidates.end());
  stillIntersecting(geometry, positions, candidates, overlaps.pairs);
  std::map<std::pair<Index, Index>, std::size_t> bySurfaces;
  for (const TrianglePair& pair : overlaps.pairs)
    ++bySurfaces[{geometry.triangleSurface[pair.first], geometry.triangleSurface[pair.second]}];
  for (const auto& [surfaces, count] : bySurfaces)
    overlaps.bySurfaces.push_back({surfaces.first, surfaces.second, count});
  if (closeDistance > 0) {
    std::erase_if(candidates, [&](const TrianglePair& pair) {
      return geometry.triangleSurface[pair.first] == geometry.triangleSurface[pair.second];
    });
    stillClose(geometry, positions, candidates, closeDistance, Crossing::Excluded, overlaps.close);
  }
  return overlaps;
}

void stillClose(const CollisionGeometry& geometry, std::span<const Vec3> positions,
                std::span<const TrianglePair> from, Scalar distance, Crossing crossing,
                std::vector<TrianglePair>& out) {
  const auto corners = [&](Index t) {
    const TriangleCorners c = geometry.corners(positions, t);
    return std::array<Vec3d, 3>{c[0].cast<double>(), c[1].cast<double>(), c[2].cast<double>()};
  };
  keepPairs(from, out, [&](const TrianglePair& pair, TrianglePairHits& hits) {
    return (crossing == Crossing::Kept ||
            !geometry.trianglesCross(positions, pair.first, pair.second, hits)) &&
           triangleDistance(corners(pair.first), corners(pair.second)) < double(distance);
  });
}

void stillIntersecting(const CollisionGeometry& geometry, std::span<const Vec3> positions,
                       std::span<const TrianglePair> from, std::vector<TrianglePair>& out) {
  keepPairs(from, out, [&](const TrianglePair& pair, TrianglePairHits& hits) {
    return geometry.trianglesCross(positions, pair.first, pair.second, hits);
  });
}

}  // namespace softbake
