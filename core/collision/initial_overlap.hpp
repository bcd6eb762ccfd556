#pragma once
/// Surfaces that intersect where the scene starts: an imported assembly whose parts touch or
/// overlap, two bodies placed into each other, a mesh that crosses itself.
///
/// Found once, before the first substep, with the same tests the collision stage uses: the broad
/// phase over every surface (each one against itself too, whatever its self-collision setting),
/// then the paper's multi-pass line–triangle test (§2.3) on every candidate pair; a pair crosses
/// when some edge of one passes through the other.
///
/// What happens to them is `settings.collisions.initial_overlap`:
/// - "set_aside" (the default): the intersecting triangle pairs are set aside. The narrow phase,
///   the response and the failsafe leave them alone, and every other pair collides from the first
///   step. At every frame's start the pairs set aside are tested again, and those found apart
///   collide like any other pair from then on (Houdini Vellum and Marvelous Designer treat
///   overlaps so). Nothing is pushed apart, so overlaps never store energy in the springs: an
///   assembly whose parts overlap by design, or a mesh that crosses itself, bakes as it is. Near
///   the set-aside pairs, the failsafe leaves alone a meeting whose own triangles intersect where
///   its substep starts, so the overlap may slide as the bodies deform without new pairs being
///   pushed. Faces of two surfaces fitted closer than the skin (`InitialOverlaps::close`), and the
///   pairs set aside once they no longer intersect, are left to the failsafe until they are two
///   skins apart (Simulator::updateSetAside).
/// - "separate": two different bodies are moved apart as wholes, without velocity, over the first
///   frames (core/collision/detangle.hpp), the response and the failsafe leaving them alone
///   meanwhile. A body cannot be moved apart from itself: its own pairs are set aside.
/// - "ignore": two surfaces that intersect at the start never collide with each other (parts
///   meant to stay glued; a body that crosses itself stops colliding with itself). Every other
///   pair of surfaces still does. Ignoring only the triangle pairs that intersect lets the
///   triangles around them, inside the other part but not crossing it, collide with it as soon as
///   they move: two glued balls were pushed 0.18 m apart within a second.

#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/scene/scene_setup.hpp"

namespace softbake {

struct CollisionGeometry;
struct SceneTopology;

/// Intersecting triangle pairs between two surfaces, or within one (first == second).
struct SurfaceOverlap {
  Index firstSurface = 0, secondSurface = 0;
  std::size_t trianglePairs = 0;
};

struct InitialOverlaps {
  std::vector<TrianglePair> pairs;         ///< sorted, lower triangle first
  std::vector<SurfaceOverlap> bySurfaces;  ///< in order of (first, second) surface
  /// Pairs of triangles of two different surfaces that do not intersect but lie closer than the
  /// `closeDistance` asked for: faces fitted onto each other. Sorted.
  std::vector<TrianglePair> close;
  bool empty() const { return pairs.empty(); }
};

/// The surface pairs of `overlaps.bySurfaces`, lower surface first, in its order (sorted): what
/// dropSurfacePairs() and a binary search read.
std::vector<std::pair<Index, Index>> overlappingSurfaces(const InitialOverlaps& overlaps);

/// The triangle pairs of `topology` that intersect with its particles at `positions`, and those of
/// different surfaces closer than `closeDistance` (none when it is 0).
InitialOverlaps findInitialOverlaps(const SceneTopology& topology,
                                    const CollisionGeometry& geometry,
                                    std::span<const Vec3> positions, Scalar closeDistance = 0);

/// Whether stillClose keeps pairs whose triangles intersect.
enum class Crossing { Excluded, Kept };

/// The pairs of `from` (sorted) whose triangles are closer than `distance` with the particles at
/// `positions`, in order, into `out`; with Crossing::Excluded, only those that do not intersect.
void stillClose(const CollisionGeometry& geometry, std::span<const Vec3> positions,
                std::span<const TrianglePair> from, Scalar distance, Crossing crossing,
                std::vector<TrianglePair>& out);

/// The pairs of `from` (sorted) whose triangles intersect with the particles at `positions`, in
/// order, into `out`.
void stillIntersecting(const CollisionGeometry& geometry, std::span<const Vec3> positions,
                       std::span<const TrianglePair> from, std::vector<TrianglePair>& out);

}  // namespace softbake
