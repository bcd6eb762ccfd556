#include "core/dynamics/integrator.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include "core/mesh/weld.hpp"
#include "core/parallel.hpp"

namespace softbake {

bool integrate(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
               SimulationState& state, std::span<Vec3> substepStart) {
  const Scalar maxSpeedSquared = topology.settings.maxSpeed * topology.settings.maxSpeed;
  const Scalar* inverseMass = topology.inverseMass.data();
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
                        const Vec3 force = particleForce(topology, forces, Index(i));
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
