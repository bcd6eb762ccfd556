#include "core/dynamics/stepper.hpp"

#include <algorithm>

#include "core/dynamics/contact_holds.hpp"
#include "core/dynamics/integrator.hpp"
#include "core/dynamics/xpbd.hpp"

namespace softbake {

void Stepper::save(std::vector<Vec3>& warmStart, std::vector<std::int32_t>& planeHolds) const {
  warmStart.clear();
  planeHolds.clear();
}

bool Stepper::fits(std::size_t warmStart, std::size_t planeHolds, std::size_t) const {
  return warmStart == 0 && planeHolds == 0;
}

void Stepper::restore(std::span<const Vec3>, std::span<const std::int32_t>) {}

namespace {

/// The paper's explicit Euler (§1.2): every force first, then one update.
class ExplicitStepper final : public Stepper {
 public:
  bool computeForces(const SceneTopology& topology, const SimulationState& state,
                     ForceBuffers& forces) override {
    computeSpringForces(topology, state, forces);
    computeVolumes(topology, state, forces);
    computePressureForces(topology, state, forces);
    return true;
  }
  bool step(const SceneTopology& topology, ForceBuffers& forces, Scalar dt, SimulationState& state,
            std::span<Vec3> substepStart) override {
    return integrate(topology, forces, dt, state, substepStart);
  }
  bool stableAtAnyStep() const override { return false; }
};

/// Plane holds caught within the solve's rounds.
class RoundHolds final : public SolveRounds {
 public:
  explicit RoundHolds(ContactHolds& holds) : holds_(holds) {}
  std::size_t afterSolve(ImplicitEuler& solver, const SimulationState& state, Scalar dt) override {
    return holds_.catchInRound(solver, state, dt);
  }

 private:
  ContactHolds& holds_;
};

/// Backward Euler, with the particles on planes held in the solve (contact_holds.hpp).
class ImplicitStepper final : public Stepper {
 public:
  explicit ImplicitStepper(const SceneTopology& topology)
      : solver_(topology), holds_(topology), velocityStart_(topology.particleCount()) {}

  bool computeForces(const SceneTopology& topology, const SimulationState& state,
                     ForceBuffers& forces) override {
    // The springs' forces come with their Jacobians in the step's one pass over the matrix.
    computeVolumes(topology, state, forces);
    computePressureForces(topology, state, forces);
    return true;
  }

  bool step(const SceneTopology& topology, ForceBuffers& forces, Scalar dt, SimulationState& state,
            std::span<Vec3> substepStart) override {
    holds_.holdFor(solver_, state, dt, true);
    const bool planes = !topology.planes.empty();
    if (planes) std::copy(state.velocity.begin(), state.velocity.end(), velocityStart_.begin());
    // Under response "none" bodies pass through planes (the paper's figure 5b): nothing is held.
    const bool holdsOnPlanes =
        planes && topology.settings.collisions.response != ResponseMode::None;
    RoundHolds rounds{holds_};
    const bool finite =
        solver_.step(topology, forces, dt, state, substepStart, holdsOnPlanes ? &rounds : nullptr);
    if (!finite || !holdsOnPlanes) return finite;
    std::size_t changed = holds_.catchImpacts(state);  // first: a hold let go is not caught again
    changed += holds_.dropWrongExpectations(solver_);
    if (changed == 0) return true;
    // Again from the start, with the particles that met a plane held and those wrongly expected
    // to let go.
    std::copy(substepStart.begin(), substepStart.end(), state.position.begin());
    std::copy(velocityStart_.begin(), velocityStart_.end(), state.velocity.begin());
    holds_.holdFor(solver_, state, dt, false);
    return solver_.stepAgain(topology, dt, state, substepStart, &rounds);
  }

  bool keepsContactsApart() const override { return true; }
  void keepApart(const SceneTopology& topology, std::span<const ContactStencil> stencils) override {
    solver_.keepApart(stencils, topology);
  }
  std::span<const char> contactsHeld() const override { return solver_.contactsHeld(); }

  std::size_t endStep() override { return holds_.update(solver_); }
  std::span<std::int32_t> planeHolds() override { return holds_.touchedPlane(); }
  bool stableAtAnyStep() const override { return true; }
  std::optional<ImplicitSolveStats> lastSolve() const override { return solver_.lastSolve(); }

  void save(std::vector<Vec3>& warmStart, std::vector<std::int32_t>& planeHolds) const override {
    warmStart.assign(solver_.warmStart().begin(), solver_.warmStart().end());
    const std::span<const std::int32_t> holds = holds_.touchedPlane();
    planeHolds.assign(holds.begin(), holds.end());
  }
  bool fits(std::size_t warmStart, std::size_t planeHolds, std::size_t particles) const override {
    return warmStart == particles && planeHolds == holds_.touchedPlane().size();
  }
  void restore(std::span<const Vec3> warmStart, std::span<const std::int32_t> planeHolds) override {
    solver_.setWarmStart(warmStart);
    std::copy(planeHolds.begin(), planeHolds.end(), holds_.touchedPlane().begin());
  }

 private:
  ImplicitEuler solver_;
  /// Contacts the next step holds. Like the solver's warm start, they carry over from one
  /// substep to the next.
  ContactHolds holds_;
  std::vector<Vec3> velocityStart_;  ///< to take a step again from its start
};

class XpbdStepper final : public Stepper {
 public:
  explicit XpbdStepper(const SceneTopology& topology) : xpbd_(topology) {}
  bool computeForces(const SceneTopology&, const SimulationState&, ForceBuffers&) override {
    return false;
  }
  bool step(const SceneTopology& topology, ForceBuffers& forces, Scalar dt, SimulationState& state,
            std::span<Vec3> substepStart) override {
    return xpbd_.step(topology, forces, dt, state, substepStart);
  }
  bool stableAtAnyStep() const override { return true; }
  int fewestAutoSubsteps(const SubstepChoice& choice) const override {
    return choice.minimumStableSubsteps;
  }

 private:
  Xpbd xpbd_;
};

}  // namespace

std::unique_ptr<Stepper> makeStepper(const SceneTopology& topology) {
  switch (topology.settings.integrator) {
    case IntegratorKind::Implicit:
      return std::make_unique<ImplicitStepper>(topology);
    case IntegratorKind::Xpbd:
      return std::make_unique<XpbdStepper>(topology);
    case IntegratorKind::Explicit:
      break;
  }
  return std::make_unique<ExplicitStepper>();
}

}  // namespace softbake
