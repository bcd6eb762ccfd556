#pragma once
/// Self-collision culling by normal cones (Volino & Magnenat-Thalmann 1994, Provot 1997).
///
/// A self-colliding surface is cut once, at setup, into patches: connected regions of up to 32
/// triangles grown breadth-first over shared edges, so each is a small disc of the
/// mesh. A patch whose triangles' normals, at the start and at the end of the substep, all lie
/// within 80° of one direction is a height field over that direction: no two of its
/// triangles can cross, so the broad phases skip its pairs within itself (pairEligible). Without
/// that, a self-colliding ball pairs every triangle with its neighbours' neighbours in every
/// step, and self-collision cost 1.6 times the bake. The cone leaves a margin below 90° because
/// the paper's response moves the particles a little after the detector found its patches; the
/// failsafe finds its own, pass by pass.
///
/// Two neighbouring patches (sharing a vertex) whose cones fit together in one cone of 80° are a
/// height field as one, and their pairs across the seam between them are skipped too: those pairs
/// are all that culling within patches leaves on a round body, which paid them in every step
/// (self-collision cost eight balls falling apart 1.6 times their bake). The merged cone is the
/// smallest around both patches' cones (its half-angle is (φ + θ₁ + θ₂)/2 for axes φ apart), a
/// bound on the normals of both, never an exact fit. That is why a patch holds at most 32
/// triangles: on a ball of 1 280 faces, patches of 128 span cones of 39–58° and a third of the
/// neighbours failed the bound; at 64 and at 32 every one passes.
///
/// The theorem also asks that the patch, seen along the cone's axis, not lie over itself (its
/// outline not cross itself). That is checked once, on the rest shape along the rest cone's axis,
/// for each patch and each pair of neighbours: where two of its triangles that share no vertex
/// overlap there, or nearly (a hundredth of their longer edge), it is never a height field,
/// whatever its normals. Two neighbouring discs of a CAD part do: a cylinder's cap and its wall,
/// welded at one vertex, the wall's other foot vertices 1.6 µm outside the cap's rim (an unwelded
/// seam), have cones that merge within 57°, and a corner of the wall went 112 µm through the cap,
/// unseen by the detector and the failsafe alike. A soft body's discs never do. A patch grown as a
/// disc of 32 triangles would have to spiral around to do it; a shape deformed into overlap from a
/// rest that did not is not checked.

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
  /// Per patch + 1: where its neighbours begin in `neighbours`, the other patches that share a
  /// vertex with it, ascending.
  std::vector<Index> neighbourStart;
  std::vector<Index> neighbours;
  /// Per patch, and per entry of `neighbours` (the two as one): 1 where the rest shape lies over
  /// itself along its cone's axis, so never flat.
  std::vector<std::uint8_t> overlapsAtRest, overlapsAtRestWith;
  std::size_t patchCount() const { return patchStart.empty() ? 0 : patchStart.size() - 1; }
};

/// Which patches are height fields over a substep, alone and with each neighbour.
struct PatchFlatness {
  std::vector<std::uint8_t> flat;      ///< per patch
  std::vector<std::uint8_t> flatWith;  ///< per entry of SelfPatches::neighbours: the two as one
  /// Per patch, its cone: the unit axis and the half-angle (radians) around it that holds its
  /// normals; kept to spare the allocation.
  std::vector<Vec3d> axis;
  std::vector<double> halfAngle;
};

/// Patches over the self-colliding soft surfaces of `geometry` (its other triangles get kNoPatch),
/// with where their rest shape, `rest` (one position per particle), lies over itself.
SelfPatches buildSelfPatches(const CollisionGeometry& geometry, std::span<const Vec3> rest);

/// out.flat[p] = 1 when patch p is a height field at both `start` and `end` (see above) and does
/// not lie over itself at rest, else 0;
/// out.flatWith likewise for each pair of neighbouring patches taken as one.
void updateFlatPatches(const CollisionGeometry& geometry, std::span<const Vec3> start,
                       std::span<const Vec3> end, PatchFlatness& out);

}  // namespace softbake
