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

int contactAccuracySubsteps(const SceneTopology& topology, std::span<const Vec3> velocities,
                            double shortestEdge) {
  const double frameTime = 1.0 / topology.settings.fps;
  double fastest = 0;
  for (const Vec3& v : velocities) fastest = std::max(fastest, double(v.norm()));
  fastest += double(topology.settings.gravity.norm()) * frameTime;
  const double reach = kContactReachFraction * (double(topology.settings.skin) + shortestEdge);
  if (!(reach > 0) || !std::isfinite(fastest)) return kMaxAutoSubsteps;
  const double substeps = std::ceil(fastest * frameTime / reach);
  return int(std::clamp(substeps, 1.0, double(kMaxAutoSubsteps)));
}

double shortestEdge(const SceneTopology& topology) {
  double shortest = std::numeric_limits<double>::infinity();
  for (const Triangle& t : topology.triangles)
    for (int k = 0; k < 3; ++k)
      shortest = std::min(
          shortest,
          double((topology.restPosition[t[(k + 1) % 3]] - topology.restPosition[t[k]]).norm()));
  return shortest;
}

}  // namespace softbake
