#include "core/dynamics/stability.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/dynamics/forces.hpp"

namespace softbake {

namespace {

/// Per body, ω² of its bulk term's one mode at the rest shape: the largest eigenvalue of
/// M⁻¹·(K/V_rest)·g·gᵀ, which is (K/V_rest)·Σ|g_i|²/m_i over the free particles (0 without one).
std::vector<double> bulkModes(const SceneTopology& topology) {
  std::vector<double> modes(topology.bodies.size(), 0.0);
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    const double stiffness = bulkStiffness(body);
    if (!(stiffness > 0)) continue;
    std::vector<Vec3d> gradient(body.particleCount, Vec3d::Zero());
    for (const Triangle& t : topology.bodyTriangles(body)) {
      const Vec3d a = topology.restPosition[t[0]].cast<double>();
      const Vec3d third = (topology.restPosition[t[1]].cast<double>() - a)
                              .cross(topology.restPosition[t[2]].cast<double>() - a) /
                          6;
      for (Index corner : t) gradient[corner - body.firstParticle] += third;
    }
    double sum = 0;
    for (Index k = 0; k < body.particleCount; ++k)
      sum += double(topology.inverseMass[body.firstParticle + k]) * gradient[k].squaredNorm();
    modes[b] = stiffness * sum;
  }
  return modes;
}

}  // namespace

StabilityBound computeStabilityBound(const SceneTopology& topology) {
  StabilityBound bound{std::numeric_limits<double>::infinity(), 0};
  // The bulk term's mode adds to each of its body's particles' bound: the largest eigenvalue of a
  // sum is at most the sum of the largest ones.
  const std::vector<double> bulk = bulkModes(topology);
  for (Index i = 0; i < topology.particleCount(); ++i) {
    if (topology.inverseMass[i] == 0) continue;
    double stiffness = 0, damping = 0;
    for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
      const Spring& spring = topology.springs[topology.springRefs[r] >> 1];
      stiffness += spring.stiffness;
      damping += spring.damping;
    }
    const double bulkMode = bulk[topology.particleBody[i]];
    if (stiffness <= 0 && damping <= 0 && bulkMode <= 0) continue;
    const double omegaSquared = 2 * stiffness * topology.inverseMass[i] + bulkMode;
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
