#pragma once
/// Bodies that start inside each other, taken apart gently: initial_overlap "separate".
///
/// An imported assembly whose parts overlap, or two bodies placed into each other, start with
/// particles of one inside the other. The paper's response pushes each such particle out by
/// itself: that deforms both bodies where they overlap, the springs store the overlap as energy,
/// and it comes back as motion. Two stiff balls placed a fifth of a diameter into each other
/// gained 6 J and flew apart at 0.8 m/s each. Houdini's Vellum detangles instead, moving points
/// apart without giving them velocity; here, since the bodies' own shapes are not what is wrong,
/// it moves each tangled body as a whole.
///
/// Every substep, per pair of tangled bodies: the edges of one that pass through a face of the
/// other with an end inside it (the edge pushes' test, findEdgeEndsInside) say which way out,
/// the sum of those faces' outward normals, and how far, the deepest end. The two bodies are
/// translated apart along that direction, split by mass like the response (a static mesh or a
/// body with pins does not move; its partner takes the whole move), by at most kDetangleSpeed·dt
/// a substep, and their velocities are left alone. A translation stores nothing in the springs,
/// so no velocity spike: the pair comes apart over the first frames and then rests in contact.
/// The response leaves a pair alone in every substep that moves it, and the failsafe until a frame
/// starts with the pair apart: the simulator names the pairs still tangled at every frame's start
/// (findInitialOverlaps).
///
/// A body tangled with itself cannot be moved apart from itself: the response separates it, as
/// before. So does it a pair of which neither side can move, or whose faces are open (no
/// inside).

#include <span>
#include <utility>
#include <vector>

#include "core/collision/initial_overlap.hpp"
#include "core/types.hpp"

namespace softbake {

struct CollisionGeometry;
struct SceneTopology;
struct SimulationState;
class CollisionDetector;

/// How fast tangled bodies are moved apart, m/s: a fifth of a metre of overlap in about 5 frames
/// at 24 fps. Slow enough to read as settling, not as a kick.
inline constexpr Scalar kDetangleSpeed = Scalar(1);

class Detangler {
 public:
  explicit Detangler(const SceneTopology& topology, const CollisionGeometry& geometry);

  /// The pairs of `overlaps` between two different surfaces of which at least one can move: the
  /// ones this stage takes apart. Replaces the previous list.
  void setTangled(const CollisionGeometry& geometry, const InitialOverlaps& overlaps);
  /// Sorted, lower surface first.
  std::span<const std::pair<Index, Index>> pairs() const { return pairs_; }
  bool any() const { return !pairs_.empty(); }
  /// The pairs the latest apply() moved apart, sorted: what the response leaves alone. A tangled
  /// pair without an edge end inside the other (nothing says which way out) is left to the
  /// response, as before this stage.
  std::span<const std::pair<Index, Index>> movedPairs() const { return moved_; }

  /// After detection, before the response: moves the tangled bodies apart (positions only).
  /// Returns how many bodies it moved.
  std::size_t apply(const SceneTopology& topology, const CollisionGeometry& geometry,
                    const CollisionDetector& detector, SimulationState& state, Scalar dt);

 private:
  std::vector<std::pair<Index, Index>> pairs_;
  std::vector<std::pair<Index, Index>> moved_;
  std::vector<char> movable_;       ///< per surface: a body without pins
  std::vector<Vec3d> direction_;    ///< per pair: Σ outward normals, first surface's way out
  std::vector<Scalar> depth_;       ///< per pair: the deepest end inside
  std::vector<Vec3d> translation_;  ///< per body, this substep
};

}  // namespace softbake
