#include "core/dynamics/integrator.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include "core/mesh/weld.hpp"

namespace softbake {

namespace {
constexpr std::size_t kParticleGrain = 2048;

bool isRunaway(const Vec3& v, Scalar maxSpeedSquared) {
  const Scalar speedSquared = v.squaredNorm();
  // Written so that NaN fails the comparison and counts as a runaway.
  return !(speedSquared <= maxSpeedSquared);
}
}  // namespace

bool integrate(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
               SimulationState& state, std::span<Vec3> substepStart) {
  const Vec3 gravity = topology.settings.gravity;
  const Scalar maxSpeedSquared = topology.settings.maxSpeed * topology.settings.maxSpeed;
  const Index* springRowStart = topology.springRowStart.data();
  const Index* springRefs = topology.springRefs.data();
  const Index* triangleRowStart = topology.triangleRowStart.data();
  const Index* triangleRefs = topology.triangleRefs.data();
  const Vec3* springForce = forces.springForce.data();
  const Vec3* triangleForce = forces.triangleForce.data();
  const Scalar* inverseMass = topology.inverseMass.data();
  const Scalar* mass = topology.mass.data();
  Vec3* x = state.position.data();
  Vec3* previous = substepStart.data();
  Vec3* v = state.velocity.data();
  std::atomic<bool> runaway{false};

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, state.particleCount(), kParticleGrain),
                    [&, x, previous, v](const tbb::blocked_range<std::size_t>& range) {
                      bool chunkRunaway = false;
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        previous[i] = x[i];
                        if (inverseMass[i] == 0) {
                          v[i].setZero();
                          continue;
                        }
                        Vec3 force = mass[i] * gravity;
                        for (Index r = springRowStart[i]; r < springRowStart[i + 1]; ++r) {
                          const Index ref = springRefs[r];
                          if (ref & 1)
                            force -= springForce[ref >> 1];
                          else
                            force += springForce[ref >> 1];
                        }
                        for (Index r = triangleRowStart[i]; r < triangleRowStart[i + 1]; ++r)
                          force += triangleForce[triangleRefs[r]];
                        v[i] += (dt * inverseMass[i]) * force;
                        x[i] += dt * v[i];
                        chunkRunaway |= isRunaway(v[i], maxSpeedSquared);
                      }
                      if (chunkRunaway) runaway.store(true, std::memory_order_relaxed);
                    });
  return !runaway.load();
}

Index findRunawayParticle(const SceneTopology& topology, const SimulationState& state) {
  const Scalar maxSpeedSquared = topology.settings.maxSpeed * topology.settings.maxSpeed;
  for (Index i = 0; i < state.particleCount(); ++i)
    if (isRunaway(state.velocity[i], maxSpeedSquared) || !state.position[i].allFinite()) return i;
  return kNoParticle;
}

}  // namespace softbake
