#pragma once
/// The mechanical energy of a scene, term by term: what the collision response may only take
/// away (issue: "the response never adds energy"), and what tests and benchmarks track per frame.

#include <array>

#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"
#include "core/stage_timer.hpp"

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

/// The energy each stage of a substep adds, in J, by Stage: how an energy gain is traced to the
/// stage that makes it (bench/results/contacts.md traced the landed engine's so).
using StageEnergies = std::array<double, kStageCount>;

/// Each lap(stage) adds the change of the scene's energy since the previous lap (or the meter's
/// start) to `stage`'s entry of `*joules`. Null `joules`: every lap does nothing. On, each lap is a
/// whole computeEnergy(), which allocates: a diagnostic, never on in a bake.
class StageEnergyMeter {
 public:
  StageEnergyMeter(StageEnergies* joules, const SceneTopology& topology,
                   const SimulationState& state);
  void lap(Stage stage);

 private:
  StageEnergies* joules_;
  const SceneTopology& topology_;
  const SimulationState& state_;
  double last_ = 0;
};

}  // namespace softbake
