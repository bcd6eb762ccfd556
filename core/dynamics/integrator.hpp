#pragma once
/// The paper's explicit Euler step (§1.2): v ← v + f/m·dt, then x ← x + v·dt with the new v.

#include "core/scene/world.hpp"

namespace softbake {

/// Sums each particle's forces (gravity, its springs, its triangles' pressure) in a fixed order,
/// then advances velocity and position; previousPosition keeps the start of the step for the
/// collision stages. Pinned particles (inverse mass 0) stay put with zero velocity.
/// Returns false when some particle's velocity is not finite or exceeds settings.maxSpeed.
bool integrate(World& world, Scalar dt);

/// The first particle whose velocity integrate() would reject, or kNoParticle.
Index findRunawayParticle(const World& world);

}  // namespace softbake
