#pragma once
/// What a simulation carries from one frame into the next, beyond the scene: enough to continue a
/// run bit for bit from a frame boundary (Simulator::checkpoint() and restore()). Everything else a
/// substep uses is either fixed by the scene or rebuilt from this (the pair cache, the substep
/// choice, the tangled surfaces), with the same result.

#include <cstdint>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

struct SimulationCheckpoint {
  SimulationState state;  ///< positions and velocities
  /// The implicit integrator's latest Δv, where its next solve starts (empty under the others).
  std::vector<Vec3> warmStart;
  /// Per particle, the plane the implicit integrator holds it on in the next step, or -1 (empty
  /// without planes or under the other integrators).
  std::vector<std::int32_t> planeHolds;
  /// The broad phase's pairs of the latest substep: "auto" substeps read the touching ones.
  std::vector<TrianglePair> touchingPairs;
  /// Surfaces still intersected each other: the failsafe and the detangler look again.
  bool tangled = false;
  std::uint64_t stepsTaken = 0;
};

}  // namespace softbake
