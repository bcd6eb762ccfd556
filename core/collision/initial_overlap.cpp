#include "core/collision/initial_overlap.hpp"

#include <map>

#include "core/collision/triangle_pair_intersection.hpp"
#include "core/enum_names.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

InitialOverlaps findInitialOverlaps(const SceneTopology& topology,
                                    std::span<const Vec3> positions) {
  const CollisionGeometry& geometry = topology.collision;
  InitialOverlaps overlaps;
  if (geometry.triangleVertices.empty()) return overlaps;
  // Boxes of a substep that does not move: each triangle's box around its corners.
  std::vector<Box3> boxes;
  updateCollisionBoxes(topology, {positions, positions}, boxes);
  std::vector<CollisionSurface> allSelfColliding = geometry.surfaces;
  for (CollisionSurface& surface : allSelfColliding) surface.selfCollision = surface.moving;
  BroadPhaseInput input = geometry.broadPhaseInput(boxes);
  input.surfaces = allSelfColliding;
  std::vector<TrianglePair> candidates;
  makeBroadPhase(BroadPhaseKind::Bvh)->findPairs(input, candidates);

  std::map<std::pair<Index, Index>, std::size_t> bySurfaces;
  TrianglePairHits hits;
  for (const TrianglePair& pair : candidates) {
    if (!intersectTrianglePair(geometry.corners(positions, pair.first),
                               geometry.corners(positions, pair.second), hits))
      continue;
    overlaps.pairs.push_back(pair);
    ++bySurfaces[{geometry.triangleSurface[pair.first], geometry.triangleSurface[pair.second]}];
  }
  for (const auto& [surfaces, count] : bySurfaces)
    overlaps.bySurfaces.push_back({surfaces.first, surfaces.second, count});
  return overlaps;
}

std::string_view initialOverlapModeName(InitialOverlapMode mode) {
  return mode == InitialOverlapMode::Ignore ? "ignore" : "separate";
}

std::vector<std::string> initialOverlapModeNames() {
  return namesOf(std::span<const InitialOverlapMode>(kInitialOverlapModes), initialOverlapModeName);
}

bool parseInitialOverlapMode(std::string_view name, InitialOverlapMode& mode) {
  return parseNamed(name, std::span<const InitialOverlapMode>(kInitialOverlapModes),
                    initialOverlapModeName, mode);
}

}  // namespace softbake
