#pragma once
/// The mutable half of a simulation: what the integrator carries from one substep to the next.
/// Positions and velocities of every particle, in the global order of its SceneTopology. Nothing
/// else survives a step, so a state and the topology it belongs to are exactly what a checkpoint
/// saves; the stages' scratch (forces, boxes, contacts) is rebuilt every substep.

#include <span>
#include <vector>

#include "core/types.hpp"

namespace softbake {

struct SceneTopology;

struct SimulationState {
  std::vector<Vec3> position;
  std::vector<Vec3> velocity;  ///< m/s

  std::size_t particleCount() const { return position.size(); }
};

/// The state at the start: rest positions, each body's initial velocity.
SimulationState initialState(const SceneTopology& topology);

/// One substep's motion of every particle, from `start` to `end`: the segments that the
/// line–triangle tests of Mesit & Guha §2.3 test. Static collision vertices are not in it.
struct SubstepMotion {
  std::span<const Vec3> start;
  std::span<const Vec3> end;
};

}  // namespace softbake
