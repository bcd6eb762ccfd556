#pragma once
/// The paper's explicit Euler step (§1.2): v ← v + f/m·dt, then x ← x + v·dt with the new v.

#include <span>

#include "core/dynamics/forces.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

/// Sums each particle's forces (gravity, its springs, its triangles' pressure) in a fixed order,
/// then advances velocity and position; `substepStart` (one entry per particle) keeps the start of
/// the step for the collision stages. Pinned particles (inverse mass 0) stay put with zero
/// velocity. Returns false when some particle's velocity is not finite or exceeds
/// settings.maxSpeed.
bool integrate(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
               SimulationState& state, std::span<Vec3> substepStart);

/// Whether a velocity counts as a blow-up: not finite, or faster than the limit.
inline bool isRunaway(const Vec3& v, Scalar maxSpeedSquared) {
  // Written so that NaN fails the comparison and counts as a runaway.
  return !(v.squaredNorm() <= maxSpeedSquared);
}

/// The first particle whose velocity integrate() would reject, or kNoParticle.
Index findRunawayParticle(const SceneTopology& topology, const SimulationState& state);

}  // namespace softbake
