#pragma once
/// The mechanical energy of a scene, term by term: what the collision response may only take
/// away (issue: "the response never adds energy"), and what tests and benchmarks track per frame.

#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

/// Joules, each summed in double in particle, spring or body order: the same for any thread count.
struct Energy {
  double kinetic = 0;  ///< Σ ½·m·|v|²
  double spring = 0;   ///< Σ ½·k·(ℓ − L)² over every spring
  /// Σ −nRT·ln(V/V_rest) over the closed bodies with gas: the work the gas would do expanding
  /// from V back to V_rest, so zero at rest volume (Matyka & Ollila's P = nRT/V).
  double gas = 0;
  /// Σ K/(2·V_rest)·(V − V_rest)² over the closed bodies with a bulk modulus: the work of the
  /// bulk term's pressure K·(1 − V/V_rest) from V back to V_rest.
  double bulk = 0;
  double gravity = 0;  ///< Σ −m·g·x: potential in the gravity field, zero at the origin
  double total() const { return kinetic + spring + gas + bulk + gravity; }
};

Energy computeEnergy(const SceneTopology& topology, const SimulationState& state);

}  // namespace softbake
