#include "core/dynamics/stability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace softbake {

StabilityBound computeStabilityBound(const SceneTopology& topology) {
  StabilityBound bound{std::numeric_limits<double>::infinity(), 0};
  for (Index i = 0; i < topology.particleCount(); ++i) {
    if (topology.inverseMass[i] == 0) continue;
    double stiffness = 0, damping = 0;
    for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
      const Spring& spring = topology.springs[topology.springRefs[r] >> 1];
      stiffness += spring.stiffness;
      damping += spring.damping;
    }
    if (stiffness <= 0 && damping <= 0) continue;
    const double omegaSquared = 2 * stiffness * topology.inverseMass[i];
    const double gamma = 2 * damping * topology.inverseMass[i];
    const double h = omegaSquared > 0
                         ? (std::sqrt(gamma * gamma + 4 * omegaSquared) - gamma) / omegaSquared
                         : 2 / gamma;
    if (h < bound.maxTimeStep) bound = {h, i};
  }
  return bound;
}

SubstepChoice chooseSubsteps(const SceneTopology& topology, int requested) {
  SubstepChoice choice;
  const double frameTime = 1.0 / topology.settings.fps;
  const StabilityBound bound = computeStabilityBound(topology);
  choice.boundTimeStep = bound.maxTimeStep;
  choice.minimumStableSubsteps = std::isfinite(bound.maxTimeStep)
                                     ? std::max(1, int(std::ceil(frameTime / bound.maxTimeStep)))
                                     : 1;
  choice.automatic = requested <= 0;
  choice.substeps =
      choice.automatic
          ? (std::isfinite(bound.maxTimeStep)
                 ? std::max(1, int(std::ceil(frameTime / (kStabilitySafety * bound.maxTimeStep))))
                 : 1)
          : requested;
  choice.timeStep = frameTime / choice.substeps;
  return choice;
}

}  // namespace softbake
