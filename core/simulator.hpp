#pragma once
/// Advances a SimulationState frame by frame over a shared, immutable SceneTopology: the fixed
/// sequence of stages of one substep.
///
///   forces (springs, volume, pressure) → integrate → collisions (detection, detangling,
///   response) → planes → failsafe
///
/// The integrator is the paper's explicit Euler (§1.2), backward Euler or XPBD
/// (settings.integrator), behind one interface (core/dynamics/stepper.hpp); the collision stages
/// after it are the same for all three.
///
/// The integrator keeps where each particle started the substep, and the collision stage sees
/// each particle's segment from there to its new position, which is what the line–triangle tests
/// of §2.3 need. Each stage's scratch (forces, boxes, pairs, contacts) is owned here and sized
/// once: nothing allocates after the first substeps.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/checkpoint.hpp"
#include "core/collision/contact.hpp"
#include "core/collision/contact_accuracy.hpp"
#include "core/collision/detangle.hpp"
#include "core/collision/detection.hpp"
#include "core/collision/failsafe.hpp"
#include "core/collision/geometry.hpp"
#include "core/collision/initial_overlap.hpp"
#include "core/collision/response.hpp"
#include "core/collision/step_contacts.hpp"
#include "core/dynamics/energy.hpp"
#include "core/dynamics/forces.hpp"
#include "core/dynamics/stability.hpp"
#include "core/dynamics/stepper.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"
#include "core/stage_timer.hpp"

namespace softbake {

/// Counts from the latest frame, for progress display and benchmarks.
struct StepStats {
  std::size_t planeContacts = 0;   ///< particle–plane contacts summed over the frame's substeps
  std::size_t candidatePairs = 0;  ///< broad-phase triangle pairs, summed over the substeps
  std::size_t contacts = 0;        ///< soft and static mesh contacts, summed over the substeps
  /// Contacts the implicit solve held apart (ContactKind::Held), summed over the substeps; not
  /// in `contacts`, which counts what the paper's test found crossing.
  std::size_t heldContacts = 0;
  CollisionResponseStats responses;  ///< summed over the substeps
  FailsafeStats failsafe;            ///< summed over the substeps
  std::size_t detangledBodies = 0;   ///< bodies the Detangler moved, summed over the substeps
  /// Triangle pairs set aside during the frame: of those that intersected at the start, the ones
  /// that still did at the frame's start (initial_overlap "set_aside").
  std::size_t setAsidePairs = 0;
  /// The energy each stage added, summed over the substeps; zeros unless measureStageEnergy(true).
  StageEnergies stageEnergy{};
};

class Simulator {
 public:
  /// Starts from `state` (one entry per particle of `topology`), or from the topology's initial
  /// state. Chooses the substeps from settings.substeps (0: automatic).
  Simulator(std::shared_ptr<const SceneTopology> topology, SimulationState state);
  explicit Simulator(std::shared_ptr<const SceneTopology> topology);
  explicit Simulator(SceneTopology topology);

  const SceneTopology& topology() const { return *topology_; }
  /// Every triangle that takes part in collisions, soft and static, in one index space.
  const CollisionGeometry& collision() const { return collision_; }
  /// For exporters and the renderer, which keep the topology for as long as they write.
  const std::shared_ptr<const SceneTopology>& sharedTopology() const { return topology_; }
  const SimulationState& state() const { return state_; }
  SimulationState& state() { return state_; }
  /// The force stage's latest results (volumes and pressures per body among them).
  const ForceBuffers& forces() const { return forces_; }
  /// The implicit integrator's latest solve; empty under the explicit one.
  std::optional<ImplicitSolveStats> lastSolve() const { return stepper_->lastSolve(); }
  /// The substeps of the latest frame ("auto" under the implicit and XPBD integrators re-chooses
  /// them per frame).
  const SubstepChoice& substeps() const { return substeps_; }
  /// Substeps run since the start.
  std::uint64_t stepsTaken() const { return stepsTaken_; }
  const StepStats& lastFrameStats() const { return stats_; }
  /// Broad-phase pairs of the latest substep.
  std::size_t lastStepCandidatePairs() const { return detector_.candidatePairs().size(); }
  /// Time each stage of every following substep (off by default); read with lastStepTimes().
  void measureStages(bool on) { measureStages_ = on; }
  const StageTimes& lastStepTimes() const { return stepTimes_; }
  /// Sum the energy each stage adds into lastFrameStats().stageEnergy (off by default): a whole
  /// energy sum per stage of every substep, for tracing an energy gain, never for a bake.
  void measureStageEnergy(bool on) { measureStageEnergy_ = on; }
  /// The contacts of the latest substep: at the end of advanceToFrame(f), those of frame f, with
  /// the particles touching a plane then (ContactKind::Plane) after the others.
  const std::vector<Contact>& contacts() const { return contacts_; }
  /// The triangle pairs that intersect at the start, found when the simulator was made; what is
  /// done with them is settings.collisions.initial_overlap.
  const InitialOverlaps& initialOverlaps() const { return initialOverlaps_; }
  /// The triangle pairs the collision stages leave alone now (initial_overlap "set_aside"), sorted.
  const std::vector<TrianglePair>& setAsidePairs() const { return detector_.setAsidePairs(); }
  /// How many pairs were set aside at the start.
  std::size_t initiallySetAsidePairs() const { return initiallySetAside_.size(); }
  /// The triangle pairs of surfaces fitted onto each other that the response leaves to the
  /// failsafe now (initial_overlap "set_aside"), sorted.
  const std::vector<TrianglePair>& fittedPairs() const { return detector_.fittedPairs(); }
  /// Whether the scene has anything the collision pipeline could find (two surfaces, or one
  /// that self-collides); planes are handled on their own.
  bool collides() const { return collides_; }

  /// One substep of `substeps().timeStep` seconds. Throws softbake::Error on a blow-up; `frame`
  /// (1-based, the frame being computed) goes into that message.
  void step(int frame);

  /// Starts a frame: clears lastFrameStats() and, under the implicit and XPBD integrators with
  /// "auto" substeps, chooses the frame's substeps again from the speeds now.
  void beginFrame();

  /// Ends a frame after its substeps: adds the particles touching a plane to contacts().
  void endFrame();

  /// All substeps from frame `frame − 1` to `frame`: beginFrame(), substeps().substeps steps,
  /// endFrame().
  void advanceToFrame(int frame);

  /// At a frame boundary (after advanceToFrame), what the next frames depend on.
  SimulationCheckpoint checkpoint() const;
  /// Continues from `checkpoint`, taken from a simulator of the same topology: the frames after
  /// it come out as they did from that one, bit for bit. Throws softbake::Error when it does not
  /// fit the topology or the integrator.
  void restore(const SimulationCheckpoint& checkpoint);

 private:
  [[noreturn]] void reportBlowUp(int frame) const;
  /// Tells the failsafe and the detangler which surfaces intersect where this frame starts.
  void nameTangledSurfaces(const InitialOverlaps& overlaps);
  /// Sets aside those of the pairs set aside at the start that intersect now.
  void updateSetAside();
  /// Faces of two surfaces closer than this at the start are fitted onto each other.
  Scalar fittedDistance() const;
  void chooseContactAccuracySubsteps();

  std::shared_ptr<const SceneTopology> topology_;
  CollisionGeometry collision_;
  SimulationState state_;
  ForceBuffers forces_;
  std::unique_ptr<Stepper> stepper_;  ///< settings.integrator
  std::vector<Vec3> substepStart_;    ///< every particle's position at the start of the substep
  double contactEdgeLength_ = 0;      ///< for "auto" substeps of the integrators stable at any step
  SubstepChoice substeps_;
  ContactAccuracyScratch contactAccuracyScratch_;
  StepStats stats_;
  CollisionDetector detector_;
  std::optional<StepContacts> stepContacts_;   ///< set when the integrator keeps contacts apart
  std::optional<CollisionFailsafe> failsafe_;  ///< set when settings.collisions.failsafe is on
  /// Set when bodies start inside each other under initial_overlap "separate".
  std::optional<Detangler> detangler_;
  InitialOverlaps initialOverlaps_;
  /// Under initial_overlap "set_aside", the surface pairs that overlapped at the start, whose edges
  /// the response does not push (core/collision/response.hpp). Sorted.
  std::vector<std::pair<Index, Index>> overlappingSurfaces_;
  /// The triangle pairs set aside at the start (all that intersected under "set_aside", a body's
  /// own under "separate"), sorted; and scratch for those still set aside.
  std::vector<TrianglePair> initiallySetAside_, setAsideScratch_;
  /// Under initial_overlap "set_aside", the pairs that may be fitted: those of different surfaces
  /// within fittedDistance() at the start, and those set aside. Sorted.
  std::vector<TrianglePair> initiallyFitted_;
  std::vector<Contact> contacts_;
  EdgePushes edgePushes_;
  bool collides_ = false;
  std::uint64_t stepsTaken_ = 0;
  bool measureStages_ = false;
  bool measureStageEnergy_ = false;
  StageTimes stepTimes_;
};

}  // namespace softbake
