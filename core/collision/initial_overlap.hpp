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
/// - "separate" (the default): two different bodies are moved apart as wholes, without velocity,
///   over the first frames (core/collision/detangle.hpp), the response and the failsafe leaving
///   them alone meanwhile; a body that crosses itself is resolved by the response like any other
///   contact, the edge pushes moving a capped fraction of an edge per substep, so it comes apart
///   over the first frames;
/// - "ignore": two surfaces that intersect at the start never collide with each other (parts
///   meant to stay glued; a body that crosses itself stops colliding with itself). Every other
///   pair of surfaces still does. Ignoring only the triangle pairs that intersect was tried: the
///   triangles around them, inside the other part but not crossing it, collided as soon as they
///   moved, and pushed two glued balls 0.18 m apart within a second.

#include <span>
#include <string_view>
#include <vector>

#include "core/collision/broad_phase.hpp"
#include "core/scene/scene_setup.hpp"

namespace softbake {

struct SceneTopology;

/// Intersecting triangle pairs between two surfaces, or within one (first == second).
struct SurfaceOverlap {
  Index firstSurface = 0, secondSurface = 0;
  std::size_t trianglePairs = 0;
};

struct InitialOverlaps {
  std::vector<TrianglePair> pairs;         ///< sorted, lower triangle first
  std::vector<SurfaceOverlap> bySurfaces;  ///< in order of (first, second) surface
  bool empty() const { return pairs.empty(); }
};

/// The triangle pairs of `topology` that intersect with its particles at `positions`.
InitialOverlaps findInitialOverlaps(const SceneTopology& topology, std::span<const Vec3> positions);

/// "separate", "ignore".
std::string_view initialOverlapModeName(InitialOverlapMode mode);
std::vector<std::string> initialOverlapModeNames();
bool parseInitialOverlapMode(std::string_view name, InitialOverlapMode& mode);

}  // namespace softbake
