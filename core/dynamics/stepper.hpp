#pragma once
/// The integrator stage of a substep behind one interface: the paper's explicit Euler, backward
/// Euler with its plane holds, or XPBD (settings.integrator). Each one owns what it carries from
/// step to step (the implicit solver's warm start, its holds) and its own retries, so the
/// simulator's substep reads as its list of stages whichever integrator runs.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "core/dynamics/forces.hpp"
#include "core/dynamics/implicit_euler.hpp"
#include "core/dynamics/stability.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

class Stepper {
 public:
  virtual ~Stepper() = default;

  /// The forces stage before step(), as this integrator reads it (springs, volumes, gas).
  /// Returns false where there is none: XPBD solves its springs and gas within its step.
  virtual bool computeForces(const SceneTopology& topology, const SimulationState& state,
                             ForceBuffers& forces) = 0;
  /// One step of `dt` seconds from `state`; `substepStart` receives the positions at its start,
  /// for the collision stages. Returns false on a blow-up (a velocity that is not finite or over
  /// settings.maxSpeed).
  virtual bool step(const SceneTopology& topology, ForceBuffers& forces, Scalar dt,
                    SimulationState& state, std::span<Vec3> substepStart) = 0;
  /// After the substep's collision stages: the particle–plane contacts it holds for the next
  /// step (0 where it holds none).
  virtual std::size_t endStep() { return 0; }
  /// Per particle, the plane it is held on or −1, which the plane stage keeps up to date; empty
  /// where the integrator holds nothing.
  virtual std::span<std::int32_t> planeHolds() { return {}; }

  /// Whether step() keeps contacts apart within its solve (keepApart()).
  virtual bool keepsContactsApart() const { return false; }
  /// The contacts the next step keeps apart, found at the state it starts from.
  virtual void keepApart(const SceneTopology&, std::span<const ContactStencil>) {}
  /// Per stencil of the latest keepApart(), whether the latest step's solve held it.
  virtual std::span<const char> contactsHeld() const { return {}; }

  /// Whether any step is stable, so that "auto" substeps follow contact accuracy alone.
  virtual bool stableAtAnyStep() const = 0;
  /// The fewest substeps "auto" may take (XPBD's springs soften past the explicit bound).
  virtual int fewestAutoSubsteps(const SubstepChoice&) const { return 1; }
  /// The implicit solver's latest solve; empty under the others.
  virtual std::optional<ImplicitSolveStats> lastSolve() const { return std::nullopt; }

  /// What the next steps depend on beyond the state, for a checkpoint: the solver's warm start
  /// and the plane holds (both empty where there are none).
  virtual void save(std::vector<Vec3>& warmStart, std::vector<std::int32_t>& planeHolds) const;
  /// Whether saved parts of those sizes fit this integrator over `particles` particles.
  virtual bool fits(std::size_t warmStart, std::size_t planeHolds, std::size_t particles) const;
  virtual void restore(std::span<const Vec3> warmStart, std::span<const std::int32_t> planeHolds);
};

/// The integrator settings.integrator names, for `topology`.
std::unique_ptr<Stepper> makeStepper(const SceneTopology& topology);

}  // namespace softbake
