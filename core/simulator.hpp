#pragma once
/// Advances a World frame by frame: the fixed sequence of stages of one substep.
///
///   forces (springs, volume, pressure) → integrate (paper §1.2) → collisions → blow-up check
///
/// The collision stage sees each particle's segment previousPosition → position, which is what the
/// line–triangle tests of §2.3 need. Nothing here allocates after construction.

#include <vector>

#include "core/collision/detection.hpp"
#include "core/collision/response.hpp"
#include "core/collision/contact.hpp"
#include "core/dynamics/stability.hpp"
#include "core/stage_timer.hpp"
#include "core/scene/world.hpp"

namespace softbake {

/// Counts from the latest frame, for progress display and benchmarks.
struct StepStats {
  std::size_t planeContacts = 0;     ///< particle–plane contacts summed over the frame's substeps
  std::size_t candidatePairs = 0;    ///< broad-phase triangle pairs, summed over the substeps
  std::size_t contacts = 0;          ///< soft and static mesh contacts, summed over the substeps
  CollisionResponseStats responses;  ///< summed over the substeps
};

class Simulator {
 public:
  /// Chooses the substeps from world.settings.substeps (0: automatic).
  explicit Simulator(World world);

  const World& world() const { return world_; }
  World& world() { return world_; }
  const SubstepChoice& substeps() const { return substeps_; }
  const StepStats& lastFrameStats() const { return stats_; }
  /// Broad-phase pairs of the latest substep.
  std::size_t lastStepCandidatePairs() const { return detector_.candidatePairs().size(); }
  /// Time each stage of every following substep (off by default); read with lastStepTimes().
  void measureStages(bool on) { measureStages_ = on; }
  const StageTimes& lastStepTimes() const { return stepTimes_; }
  /// The contacts of the latest substep: at the end of advanceToFrame(f), those of frame f.
  const std::vector<Contact>& contacts() const { return contacts_; }
  /// Whether the scene has anything the collision pipeline could find (two surfaces, or one
  /// that self-collides); planes are handled on their own.
  bool collides() const { return collides_; }

  /// One substep of `substeps().timeStep` seconds. Throws softbake::Error on a blow-up; `frame`
  /// (1-based, the frame being computed) goes into that message.
  void step(int frame);

  /// All substeps from frame `frame − 1` to `frame`.
  void advanceToFrame(int frame);

 private:
  [[noreturn]] void reportBlowUp(int frame) const;

  World world_;
  SubstepChoice substeps_;
  StepStats stats_;
  CollisionDetector detector_;
  std::vector<Contact> contacts_;
  bool collides_ = false;
  bool measureStages_ = false;
  StageTimes stepTimes_;
};

}  // namespace softbake
