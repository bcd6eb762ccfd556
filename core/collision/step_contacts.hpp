#pragma once
/// The contacts an implicit step keeps apart within its solve (core/dynamics/contact_springs.hpp),
/// found once, up front, at the state the step starts from.
///
/// Each collision triangle's box covers where its corners are at the start and where their own
/// motion and gravity would take them over the step, grown by the gap and by half of how far that
/// travel departs from the body's mean travel (the solve changes the motion it predicts), so a pair
/// the step can bring together is a candidate; the broad phase is the detector's, through its pair
/// cache (any of the broad phases, the paper's subdivided boxes and box hash among them). Each
/// candidate pair gives its corners against the other triangle: a vertex whose foot on the
/// triangle's plane lies on the triangle, in front of it (outside, for a closed surface; on its
/// side at the start, for an open one), and within the gap plus its reach is a stencil; a foot
/// further off the triangle than the gap plus the reach, at the start and as predicted, is not.
/// The gap is the skin, or an open body's thickness (the failsafe's, so the two stages keep the
/// same distance). A stencil asks the plane to keep the vertex what keeps it the gap from the
/// triangle: less when its foot lies off the triangle, and never more than the scene placed it
/// from its own surface, so no stencil pushes a body that rests as the scene made it.
///
/// What it leaves out is what the paper's line–triangle test and response, then the failsafe,
/// still catch after the step: edge against edge, a vertex that slides over a triangle's edge, and
/// whatever moved further than predicted. The pairs the detector sets aside or ignores are left
/// alone here too; a vertex its own surface placed within the gap of a triangle (the walls and
/// fillets of a CAD part, a folded sheet) is kept no closer than it was placed, and once behind
/// such a triangle of a closed surface (inside it), held where it is. The detector's
/// fitted pairs (faces of two parts fitted closer than the skin) are the failsafe's, but a vertex
/// only they bring is held no nearer the face it was placed in front of than it was placed, or
/// than it has come, and once behind it where it is: no deeper, never pushed out. (Between
/// surfaces that overlapped at the start, one still in front gives.) Their stencils are marked
/// `fitted`, and the solve never raises their force beyond the spring's own
/// (core/dynamics/contact_springs.hpp). Each (vertex, triangle) the pairs bring is measured once,
/// by chunks of triangles whose buffers are joined in order and sorted by (vertex, triangle), so
/// the stencils are the same for any thread count.

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/broad_phase/pair_cache.hpp"
#include "core/collision/contact.hpp"
#include "core/collision/geometry.hpp"
#include "core/parallel.hpp"
#include "core/scene/contact_stencil.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

class CollisionDetector;

class StepContacts {
 public:
  /// A foot this far outside a triangle, in barycentric terms, still counts: a vertex over the
  /// edge between two triangles belongs to both.
  static constexpr Scalar kFootTolerance = Scalar(0.02);

  StepContacts(const SceneTopology& topology, const CollisionGeometry& geometry);

  /// The stencils of a step of `dt` from `state`, sorted by vertex, then triangle. `overlapping`:
  /// the surface pairs that intersected at the start (sorted, lower first), under
  /// initial_overlap "set_aside"; between them a fitted vertex in front of its mate gives.
  std::span<const ContactStencil> find(const SceneTopology& topology,
                                       const CollisionGeometry& geometry,
                                       CollisionDetector& detector, const SimulationState& state,
                                       Scalar dt,
                                       std::span<const std::pair<Index, Index>> overlapping = {});

  /// Appends a ContactKind::Held contact for each stencil of the latest find() that `held` (one
  /// flag per stencil) marks, at the vertex's position in `positions`.
  void appendHeld(const CollisionGeometry& geometry, std::span<const char> held,
                  std::span<const Vec3> positions, std::vector<Contact>& contacts) const;

 private:
  struct Found {
    std::uint64_t key;  ///< vertex, triangle
    ContactStencil stencil;
  };
  /// Appends the stencil of collision vertex `v` against collision triangle `triangle`, if any.
  void tryVertex(const SceneTopology& topology, const CollisionGeometry& geometry,
                 std::span<const Vec3> start, std::span<const std::pair<Index, Index>> overlapping,
                 Index v, Index triangle, std::vector<Found>& out) const;

  std::vector<Scalar> gap_;           ///< per surface: the distance its contacts keep
  std::vector<Index> vertexSurface_;  ///< per collision vertex: its surface
  /// Per surface, whether the detector's fitted pairs name it, at the latest find().
  std::vector<char> fittedSurface_;
  std::vector<Vec3> predicted_;  ///< per particle: where its motion and gravity take it
  /// Per collision vertex: half of how far its predicted travel departs from its body's mean.
  std::vector<Scalar> reach_;
  std::vector<Box3> vertexBoxes_, boxes_;
  std::unique_ptr<BroadPhase> broadPhase_;  ///< when the detector keeps no pair cache
  PairCache pairCache_;
  std::vector<TrianglePair> pairs_;
  /// Per collision triangle, the triangles paired with it: from partner_[partnerStart_[t]].
  std::vector<Index> partnerStart_, partnerFill_, partner_;
  ChunkBuffers<Index> chunkCorners_;  ///< per chunk of triangles: a triangle's partners' corners
  ChunkBuffers<Index> chunkSeen_;     ///< and the set that drops their repeats
  ChunkBuffers<Found> chunkFound_;
  std::vector<Found> found_;
  std::vector<ContactStencil> stencils_;
};

}  // namespace softbake
