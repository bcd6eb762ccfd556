#pragma once
/// The last collision stage of a substep: whatever the paper's response (§2.4) and the plane pass
/// left, no triangle passes through another during the substep (Bridson, Fedkiw & Anderson 2002,
/// "Robust treatment of collisions, contact and friction for cloth animation", §4 and §7.4).
///
/// Why a failsafe after the paper's pipeline rather than instead of it: the paper's response is a
/// per-particle projection, measured on each contact by itself. In a pile, under a heavy load or
/// against a thin sheet, one particle's correction pushes another through a third surface, and
/// nothing measures the result again; the crossings that stay become tangles the edge pushes fight
/// with large forces, and those blew runs up. Here every particle moves on a straight line from
/// where the substep started, which was free of crossings, to where the substep left it, and
/// continuous tests (core/collision/continuous_collision.hpp) find every vertex–face and edge–edge
/// meeting on the way:
///
/// 1. Impulses, in passes: each meeting gets an inelastic, mass-weighted correction along its
///    normal that leaves the two primitives `separation` apart at the end of the substep (a
///    displacement), and takes from their velocities what approach they had along it (§7.1),
///    applied one after the other in a fixed order, with Coulomb friction bounded by the same
///    impulse (§7.2). It conserves momentum; static triangles and pinned particles do not move. A
///    later pass measures again only the pairs of triangles the pass before it moved. An open
///    surface (a sheet, a flag) has no inside to keep anything out of, so it gets a two-sided skin
///    instead: its material's thickness. Primitives of a sheet meet anything that comes within its
///    thickness, and are left that far apart.
/// 2. Impact zones, when passes of impulses leave meetings: the particles of every meeting are
///    merged into zones, and each zone moves as one over the substep, with its mean velocity
///    (momentum conserved). A translated zone cannot cross itself, zones that meet are merged,
///    and a zone that holds a pinned particle, a static vertex or a particle on a plane stays
///    where it started. The zones grow until nothing meets. A translating pass that finds the very
///    meetings of the pass before cannot part them, so the zones then stay where they started.
/// 3. Should that still leave meetings after many passes, every body of a meeting goes back to
///    where the substep started, with every body fitted onto it (an assembly goes back whole), and
///    moves from there as one, lifted onto a ground plane it reached; where moving cannot part
///    them (a pin, a static mesh, a group that meets again as it was) it stays there at rest. It
///    is measured again, until nothing meets: the start was free of crossings, so a body there
///    meets nothing else that is there, and each pass moves a body, joins two groups or puts one
///    to rest. Bodies that met nothing keep their substep. Counted, never expected.
///
/// A meeting of two primitives that were closer than the separation in the scene's initial state
/// (a mesh finer than the skin, a sheet thinner than its thickness, parts of an assembly fitted
/// tighter than the skin) is left alone unless one passes more than the separation through the
/// other: the scene was made so, and holding them apart would push the bodies away from their
/// shapes and fits, and each push into the next fit (an engine of 115 parts held the failsafe at
/// its last stage in every substep). Less than that is rounding and the fit's own give: faces
/// fitted onto each other swap sides by it in every substep. Unless the fitted triangles then
/// intersect, or touch, where they did not at the start: near-copies of one surface in another
/// (a spider's two shells 13 µm apart) cross by their nearly parallel edges as soon as they turn
/// against each other, and two stacked faces lifted to one height above the ground overlap in a
/// plane; neither is a side any test sees change. Such a pair is not pushed (pushing fitted faces
/// apart blew an assembly of 55 fitted parts up): its two triangles go into one zone (stage 2),
/// which keeps them as they were at the start. A meeting already within its tolerance where the
/// substep starts that ends it no closer on the same side is left alone too: along its normal
/// nothing crossed, and no stage here can leave it further apart than the start. Unless its
/// triangles end intersecting where they did not at the start, between surfaces that did not
/// overlap in the scene's initial state: a vertex sliding along a face that turns up under its
/// path ends under the face no closer to its foot, and an engine's shell passed through itself so.
/// Those triangles go into one zone too.
///
/// Surfaces that intersect each other are not held apart: holding them would hold them in their
/// tangle. The simulator names them (leaveTangled) where the scene starts and again at every frame
/// while any are left, and the detangler (core/collision/detangle.hpp) or the paper's response
/// separates them (initial_overlap "separate", over the first frames); from the frame they are
/// found apart, this stage holds them apart. A meeting
/// whose own triangles intersected at its start is left alone too, when its surfaces overlapped in
/// the scene's initial state or it is fitted (an overlap set aside slides out of itself by such
/// meetings); between any other surfaces that crossing is a miss, and leaving its meetings alone
/// let it deepen substep by substep. Nor is such a meeting pushed: its normal, oriented where the
/// substep starts, points the crossed way, and an impulse drove an engine's parts 0.39 mm into
/// each other in one substep. Its crossing triangles go into one zone (stage 2), which keeps the
/// crossing as it was. Surfaces ignored under
/// "ignore" never meet. Otherwise the same pairs as the detector's, the same eligibility
/// (self-collision only for surfaces that have it on).
///
/// Detection runs in parallel over the broad phase's pairs; the meetings are sorted before any is
/// applied, so the result is the same for any number of threads. Self-collision is culled by
/// normal cones (core/collision/self_patches.hpp) over each pass's own motion: impulses and zones
/// turn triangles, and with the detector's patches a zone shifted in a body's fold let two of its
/// triangles cross unseen.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/broad_phase/pair_cache.hpp"
#include "core/collision/continuous_collision.hpp"
#include "core/collision/initial_overlap.hpp"
#include "core/collision/self_patches.hpp"
#include "core/parallel.hpp"
#include "core/types.hpp"

namespace softbake {

struct SceneTopology;
struct CollisionGeometry;
struct SimulationState;
class CollisionDetector;

struct Body;

/// The two-sided skin of an open body (a sheet has no inside): its material's thickness, at most
/// a quarter of its short edges; 0 for a closed body.
double openSurfaceThickness(const SceneTopology& topology, const Body& body);

struct FailsafeStats {
  std::size_t impacts = 0;        ///< meetings found over all passes
  std::size_t zoneParticles = 0;  ///< particles moved as part of an impact zone
  std::size_t frozen = 0;         ///< substeps that reached stage 3
  std::size_t frozenBodies = 0;   ///< bodies stage 3 put back where their substep started, at rest
  std::size_t bodiesMovedAsOne = 0;  ///< bodies stage 3 moved as one group from their start
  std::size_t passes = 0;            ///< detection passes run

  FailsafeStats& operator+=(const FailsafeStats& other) {
    impacts += other.impacts;
    zoneParticles += other.zoneParticles;
    frozen += other.frozen;
    frozenBodies += other.frozenBodies;
    bodiesMovedAsOne += other.bodiesMovedAsOne;
    passes += other.passes;
    return *this;
  }
};

/// One meeting of two primitives: vertices in the order of Impact::weight.
struct FailsafeImpact {
  std::array<Index, 4> vertex{};
  Index face = 0;         ///< the struck triangle of a vertex–face meeting
  bool edge = false;      ///< an edge–edge meeting
  double separation = 0;  ///< how far apart it leaves them: the thicker side's thickness, or more
  double friction = 0;    ///< Coulomb coefficient: the geometric mean of the two surfaces'
  Impact impact;
};

/// How many passes each stage gets. The defaults follow Bridson et al., who use a handful of
/// impulse passes: most meetings are single and one pass settles them, a second measures what the
/// first pushed into others. Zones translate with their momentum for most of their passes: a
/// zone grows by its neighbours one pass at a time, and an assembly of fitted parts is a long
/// chain of them (an engine of 115 parts needed more than 8 passes, and zones left at their start
/// took their velocity with them: 66 N s in one frame, and the falling engine hung in the air).
/// The last few passes leave a zone where it started (with its momentum there), which frees it.
struct FailsafePasses {
  int impulses = 4;
  int translatingZones = 60;
  int zones = 64;  ///< in all, translating ones included
};

class CollisionFailsafe {
 public:
  explicit CollisionFailsafe(const SceneTopology& topology, const CollisionGeometry& geometry,
                             FailsafePasses passes = {});

  /// Corrects state (positions and velocities) so that no eligible triangles meet on the way from
  /// `start`, with `dt` the substep. `detector` supplies the surface pairs to ignore.
  FailsafeStats apply(const SceneTopology& topology, const CollisionGeometry& geometry,
                      CollisionDetector& detector, std::span<const Vec3> start,
                      SimulationState& state, double dt);

  /// The surfaces (pairs, or one with itself) that `overlaps` found intersecting now: this stage
  /// leaves them to the response until the next call, which names those still tangled.
  void leaveTangled(const InitialOverlaps& overlaps);
  bool anyTangled() const { return !tangled_.empty(); }

  /// The surfaces (pairs, or one with itself) that intersected in the scene's initial state. Only
  /// between those may a meeting whose triangles already intersect where its substep starts be
  /// left alone (so that an overlap set aside may slide out of itself); between any others such a
  /// crossing is a miss, and its triangles move as one zone so that it does not deepen.
  void leaveOverlapping(const InitialOverlaps& overlaps);

  /// Distance two meeting primitives are left apart, scene units.
  double separation() const { return separation_; }
  /// Distance within which two primitives meet.
  double tolerance() const { return tolerance_; }

 private:
  bool findImpacts(const SceneTopology& topology, const CollisionGeometry& geometry,
                   CollisionDetector& detector, std::span<const Vec3> start,
                   std::span<const Vec3> end, bool onlyMoved);
  /// Crossing: the line–triangle test finds an edge through a face. Touching: that, or the two
  /// triangles lie within rounding of each other without sharing a corner (coplanar overlaps).
  enum class Contact { Crossing, Touching };
  /// A pair of triangles around the meeting's primitives (the vertex's against the face, the
  /// edges' against each other) in `contact` with the particles at `at`, if any.
  std::optional<TrianglePair> crossingTriangles(const CollisionGeometry& geometry,
                                                std::span<const Vec3> at,
                                                const FailsafeImpact& impact,
                                                Contact contact) const;
  /// Whether the meeting's primitives were closer than its separation in the scene's initial
  /// state: a mesh finer than the skin, a part thinner than it, parts of an assembly fitted tighter
  /// than it were made that close.
  bool closeAtRest(const SceneTopology& topology, const CollisionGeometry& geometry,
                   const FailsafeImpact& impact) const;
  /// Whether the meeting's two surfaces intersected in the scene's initial state.
  bool betweenOverlapping(const CollisionGeometry& geometry, const FailsafeImpact& impact) const;
  /// Whether the meeting's first primitive ends the substep more than `tolerance` on the other
  /// side of the second.
  static bool crosses(const CollisionGeometry& geometry, std::span<const Vec3> start,
                      std::span<const Vec3> end, const FailsafeImpact& impact, double tolerance);
  /// Whether the meeting's primitives end the substep no closer than they started it, on the same
  /// side, along its normal (within rounding): nothing crossed. Within its tolerance at the start,
  /// no stage here could leave them further apart than the start, where a zone that stays puts
  /// them; within it only later, they came no closer than rounding takes them.
  static bool notClosing(const CollisionGeometry& geometry, std::span<const Vec3> start,
                         std::span<const Vec3> end, const FailsafeImpact& impact);
  void applyImpulses(const SceneTopology& topology, const CollisionGeometry& geometry,
                     SimulationState& state);
  void keepAbovePlanes(const SceneTopology& topology, SimulationState& state, double dt);
  /// Joins the bodies that the detector's fitted pairs join into assemblies (bodyRoot_): once per
  /// substep that reaches stage 3, as the fitted pairs change only between frames.
  void joinFittedBodies(const SceneTopology& topology, const CollisionGeometry& geometry,
                        const CollisionDetector& detector);
  /// Stage 3: the bodies of the latest meetings, each with every body that a meeting or a fit
  /// (joinFittedBodies()) joins to it, go back where the substep started; each such group moves
  /// from there as one, with its mean displacement and velocity (lifted onto a plane it would
  /// reach, without its speed into the plane), or stays there at rest where that cannot part it.
  /// Counts the bodies in `stats`.
  void putBodiesBack(const SceneTopology& topology, const CollisionGeometry& geometry,
                     std::span<const Vec3> start, SimulationState& state, FailsafeStats& stats);
  /// Calls `visit` with the vertices of each of the latest meetings: a meeting's four, a
  /// crossing's six corners.
  template <class Visit>
  void forEachMeeting(const CollisionGeometry& geometry, Visit&& visit) const;
  /// Merges the meetings' particles into zones and moves each zone as one; returns the particles
  /// in zones. With `stayFor` (the substep, s) above 0, each zone stays where it started instead,
  /// with the momentum it had there.
  std::size_t moveZones(const SceneTopology& topology, const CollisionGeometry& geometry,
                        std::span<const Vec3> start, SimulationState& state, double stayFor);
  Index zoneOf(Index v);
  void clearZones();
  /// Whether impacts_ and crossings_ hold the meetings of the latest translating zone pass.
  bool sameMeetings() const;

  FailsafePasses passes_;
  double tolerance_, separation_;
  std::vector<double> thickness_;  ///< per surface: an open body's material thickness, else 0
  double margin_ = 0;              ///< boxes grow by it: the tolerance or the largest thickness
  std::vector<Box3> boxes_;        ///< per collision triangle, over the substep
  std::vector<Box3> pathBoxes_;    ///< per collision vertex, over the substep
  std::unique_ptr<BroadPhase> broadPhase_;
  PairCache pairCache_;  ///< only when the detector keeps none
  std::vector<TrianglePair> pairs_;
  PatchFlatness patchFlat_;  ///< the self-collision patches that are flat over this pass
  std::vector<std::pair<Index, Index>> tangled_;      ///< surface pairs, sorted
  std::vector<std::pair<Index, Index>> overlapping_;  ///< surface pairs, sorted
  /// Per collision triangle: bit k set when it owns its corner k, bit 3 + k its edge k → k+1. A
  /// vertex or an edge is tested from the lowest-numbered triangle that holds it, once per pair
  /// of surfaces (the triangles around it all pair with the same ones).
  std::vector<std::uint8_t> owns_;
  ChunkBuffers<FailsafeImpact> chunkImpacts_;
  std::vector<FailsafeImpact> impacts_;
  /// Triangle pairs of fitted meetings that intersect where the substep ends but did not where it
  /// started, and of meetings between surfaces apart at the scene's start whose triangles
  /// intersect where it starts, sorted: each goes into a zone whole.
  std::vector<TrianglePair> crossings_, lastCrossings_;
  std::vector<std::uint8_t> verdicts_;    ///< scratch, per meeting found
  std::vector<TrianglePair> crossingOf_;  ///< scratch, per meeting found
  /// The primitives of the latest translating zone pass's meetings, sorted as impacts_ is.
  std::vector<std::array<Index, 4>> lastMeetings_;
  std::vector<std::uint8_t> moved_;          ///< per particle: moved by this failsafe's latest pass
  std::vector<std::uint8_t> triangleMoved_;  ///< per collision triangle: a corner in moved_
  std::vector<std::uint8_t> onPlane_;        ///< per particle: kept above a plane this substep
  std::vector<Index> zoneParent_;   ///< union–find over particles; zoneParent_[v] == v: a root
  std::vector<Index> zoneMembers_;  ///< scratch: particles of zones, grouped by root
  std::vector<std::uint8_t> inZone_;
  enum BodyBack : std::uint8_t { kBodyFree, kBodyMovedAsOne, kBodyAtRest };
  std::vector<std::uint8_t> bodyBack_;  ///< per body: what this substep's stage 3 did with it
  std::vector<Index> bodyGroupSize_;    ///< per body: the bodies of the group it last moved with
  /// Scratch: union–find over bodies by their fitted pairs and their meetings in stage 3.
  std::vector<Index> bodyRoot_;
  /// Scratch, per group root of bodyRoot_: a meeting of this pass holds it, it must rest, it holds
  /// a body stage 3 had not moved, and its mass, Σ m·displacement and Σ m·velocity (then the mean
  /// displacement and velocity it moves with), and its lowest height above the plane at hand.
  std::vector<std::uint8_t> groupMeets_, groupRests_, groupNew_;
  std::vector<double> groupMass_, groupLowest_;
  std::vector<Index> groupBodies_;
  std::vector<Vec3d> groupShift_, groupMomentum_;
  std::vector<std::uint8_t>
      zoneFixed_;  ///< per zone root: holds a pinned, static or plane particle
  /// Per particle: a staying zone placed it, and took the substep's gravity from its velocity.
  std::vector<std::uint8_t> gravityTaken_;
  std::vector<double> zoneMass_;  ///< per zone root, and its momentum over the substep:
  std::vector<Vec3d> zoneShift_, zoneVelocity_;  ///< Σ m·displacement, Σ m·velocity
};

}  // namespace softbake
