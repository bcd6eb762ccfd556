#include "core/dynamics/energy.hpp"

#include <algorithm>
#include <cmath>

#include "core/dynamics/forces.hpp"

namespace softbake {

Energy computeEnergy(const SceneTopology& topology, const SimulationState& state) {
  Energy energy;
  const Vec3d gravity = topology.settings.gravity.cast<double>();
  for (std::size_t i = 0; i < state.particleCount(); ++i) {
    const double mass = topology.mass[i];
    energy.kinetic += 0.5 * mass * state.velocity[i].cast<double>().squaredNorm();
    energy.gravity -= mass * gravity.dot(state.position[i].cast<double>());
  }
  for (const Spring& spring : topology.springs) {
    const double stretch =
        (state.position[spring.b] - state.position[spring.a]).cast<double>().norm() -
        spring.restLength;
    energy.spring += 0.5 * double(spring.stiffness) * stretch * stretch;
  }
  ForceBuffers forces(topology);
  computeVolumes(topology, state, forces);
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    if (!body.closed) continue;
    // The pressure law is clamped at kMinVolumeFraction; so is its energy.
    const double volume = std::max(forces.bodyVolume[b], kMinVolumeFraction * body.restVolume);
    if (body.gasAmount > 0) energy.gas -= body.gasAmount * std::log(volume / body.restVolume);
    const double change = volume - body.restVolume;
    energy.bulk += 0.5 * bulkStiffness(body) * change * change;
  }
  return energy;
}

StageEnergyMeter::StageEnergyMeter(StageEnergies* joules, const SceneTopology& topology,
                                   const SimulationState& state)
    : joules_(joules), topology_(topology), state_(state) {
  if (joules_) last_ = computeEnergy(topology_, state_).total();
}

void StageEnergyMeter::lap(Stage stage) {
  if (!joules_) return;
  const double now = computeEnergy(topology_, state_).total();
  (*joules_)[int(stage)] += now - last_;
  last_ = now;
}

}  // namespace softbake
