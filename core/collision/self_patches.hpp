#pragma once
/// Self-collision culling by normal cones (Volino & Magnenat-Thalmann 1994, Provot 1997).
///
/// A self-colliding surface is cut once, at setup, into patches: connected regions of up to 128
/// triangles grown breadth-first over shared edges, so each is a small disc of the
/// mesh. A patch whose triangles' normals, at the start and at the end of the substep, all lie
/// within 80° of one direction is a height field over that direction: no two of its
/// triangles can cross, so the broad phases skip its pairs within itself (pairEligible). Without
/// that, a self-colliding ball pairs every triangle with its neighbours' neighbours in every
/// step, and self-collision cost 1.6 times the bake. The cone leaves a margin below 90° because
/// the failsafe reads the detector's patches with positions the response has moved a little.
///
/// The theorem also asks that the patch's outline, seen along the cone's axis, not cross itself;
/// that is not checked. A patch grown as a disc of 128 triangles would have to spiral around to
/// break it, and its normals then leave the cone.

#include <cstdint>
#include <span>
#include <vector>

#include "core/types.hpp"

namespace softbake {

struct CollisionGeometry;

inline constexpr Index kNoPatch = ~Index(0);

struct SelfPatches {
  std::vector<Index> trianglePatch;  ///< per collision triangle: its patch, or kNoPatch
  std::vector<Index> patchStart;     ///< per patch + 1: where its triangles begin in `triangles`
  std::vector<Index> triangles;      ///< patch by patch
  std::size_t patchCount() const { return patchStart.empty() ? 0 : patchStart.size() - 1; }
};

/// Patches over the self-colliding soft surfaces of `geometry` (its other triangles get kNoPatch).
SelfPatches buildSelfPatches(const CollisionGeometry& geometry);

/// flat[p] = 1 when patch p is a height field at both `start` and `end` (see above), else 0.
void updateFlatPatches(const CollisionGeometry& geometry, std::span<const Vec3> start,
                       std::span<const Vec3> end, std::vector<std::uint8_t>& flat);

}  // namespace softbake
