#include "core/dynamics/implicit_euler.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/dynamics/integrator.hpp"

namespace softbake {

namespace {
constexpr std::size_t kSpringGrain = 4096;
constexpr std::size_t kParticleGrain = 2048;
/// Particles per dot-product chunk: the chunks, not the threads, fix the summation order.
constexpr std::size_t kDotChunk = 4096;

/// Runs body(i) for every particle in parallel.
template <class Body>
void forEachParticle(std::size_t count, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kParticleGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) body(Index(i));
                    });
}
}  // namespace

ImplicitEuler::ImplicitEuler(const SceneTopology& topology)
    : springBlock_(topology.springs.size(), Block::Zero()),
      springVelocity_(topology.springs.size(), Vec3::Zero()),
      rhs_(topology.particleCount(), Vec3::Zero()),
      inverseDiagonal_(topology.particleCount(), Vec3::Zero()),
      deltaV_(topology.particleCount(), Vec3::Zero()),
      residual_(topology.particleCount(), Vec3::Zero()),
      preconditioned_(topology.particleCount(), Vec3::Zero()),
      direction_(topology.particleCount(), Vec3::Zero()),
      product_(topology.particleCount(), Vec3::Zero()),
      chunkSum_((topology.particleCount() + kDotChunk - 1) / kDotChunk, 0.0) {}

void ImplicitEuler::assemble(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
                             const SimulationState& state) {
  // Per spring: its block S and h²·K_s·(v_b − v_a).
  const Spring* springs = topology.springs.data();
  const Vec3* x = state.position.data();
  const Vec3* v = state.velocity.data();
  Block* blocks = springBlock_.data();
  Vec3* springVelocity = springVelocity_.data();
  const Scalar h = dt, h2 = dt * dt;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topology.springs.size(), kSpringGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t s = range.begin(); s != range.end(); ++s) {
                        const Spring& spring = springs[s];
                        const Vec3 d = x[spring.b] - x[spring.a];
                        const Scalar length = d.norm();
                        if (!(length > Scalar(0))) {
                          blocks[s].setZero();
                          springVelocity[s].setZero();
                          continue;
                        }
                        const Vec3 axis = d / length;
                        const Block along = axis * axis.transpose();
                        // ∂f_a/∂x_b: k·(d̂d̂ᵀ + (1 − L/l)(I − d̂d̂ᵀ)), transverse part clamped at 0.
                        const Scalar transverse =
                            std::max(Scalar(0), Scalar(1) - spring.restLength / length);
                        const Block stiffness =
                            spring.stiffness * (along + transverse * (Block::Identity() - along));
                        blocks[s] = (h * spring.damping) * along + h2 * stiffness;
                        springVelocity[s] = h2 * (stiffness * (v[spring.b] - v[spring.a]));
                      }
                    });

  // Per particle: b = h·f₀ + h²·K·v₀, and the Jacobi preconditioner.
  const Scalar* mass = topology.mass.data();
  const Scalar* inverseMass = topology.inverseMass.data();
  forEachParticle(topology.particleCount(), [&](Index i) {
    if (inverseMass[i] == 0) {
      rhs_[i].setZero();
      inverseDiagonal_[i].setZero();
      return;
    }
    Vec3 b = h * particleForce(topology, forces, i);
    Vec3 diagonal = Vec3::Constant(mass[i]);
    for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
      const Index ref = topology.springRefs[r];
      const Index s = ref >> 1;
      // The `a` end gets K_s·(v_b − v_a); the `b` end the opposite.
      if (ref & 1)
        b -= springVelocity_[s];
      else
        b += springVelocity_[s];
      diagonal += springBlock_[s].diagonal();
    }
    rhs_[i] = b;
    inverseDiagonal_[i] = diagonal.cwiseInverse();
  });
}

void ImplicitEuler::multiply(const SceneTopology& topology, const std::vector<Vec3>& in,
                             std::vector<Vec3>& out) const {
  const Scalar* mass = topology.mass.data();
  const Scalar* inverseMass = topology.inverseMass.data();
  const Spring* springs = topology.springs.data();
  forEachParticle(topology.particleCount(), [&](Index i) {
    if (inverseMass[i] == 0) {  // the constraint filter: pinned rows are zero
      out[i].setZero();
      return;
    }
    Vec3 sum = mass[i] * in[i];
    for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
      const Index ref = topology.springRefs[r];
      const Spring& spring = springs[ref >> 1];
      const Index other = (ref & 1) ? spring.a : spring.b;
      // A pinned neighbour's Δv is zero: its column is filtered out too.
      const Vec3 otherIn = inverseMass[other] == 0 ? Vec3::Zero() : in[other];
      sum += springBlock_[ref >> 1] * (in[i] - otherIn);
    }
    out[i] = sum;
  });
}

double ImplicitEuler::dot(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  const std::size_t count = a.size();
  tbb::parallel_for(std::size_t(0), chunkSum_.size(), [&](std::size_t chunk) {
    double sum = 0;
    const std::size_t end = std::min(count, (chunk + 1) * kDotChunk);
    for (std::size_t i = chunk * kDotChunk; i < end; ++i)
      sum +=
          double(a[i].x()) * b[i].x() + double(a[i].y()) * b[i].y() + double(a[i].z()) * b[i].z();
    chunkSum_[chunk] = sum;
  });
  double total = 0;
  for (double sum : chunkSum_) total += sum;
  return total;
}

void ImplicitEuler::solve(const SceneTopology& topology) {
  // Preconditioned CG (Shewchuk 1994, B3), warm-started from the previous step's Δv: successive
  // steps change velocity alike, so the first residual is already small. Pinned entries stay 0.
  const std::size_t n = topology.particleCount();
  multiply(topology, deltaV_, product_);
  forEachParticle(n, [&](Index i) {
    residual_[i] = rhs_[i] - product_[i];
    preconditioned_[i] = inverseDiagonal_[i].cwiseProduct(residual_[i]);
    direction_[i] = preconditioned_[i];
  });
  const double rhsNorm = std::sqrt(dot(rhs_, rhs_));
  double rz = dot(residual_, preconditioned_);
  stats_ = {};
  if (rhsNorm == 0) {
    forEachParticle(n, [&](Index i) { deltaV_[i].setZero(); });
    return;
  }
  const double tolerance = kTolerance * rhsNorm;
  stats_.relativeResidual = std::sqrt(dot(residual_, residual_)) / rhsNorm;
  if (stats_.relativeResidual <= kTolerance) return;
  for (int iteration = 1; iteration <= kMaxIterations; ++iteration) {
    multiply(topology, direction_, product_);
    const double curvature = dot(direction_, product_);
    if (!(curvature > 0)) break;  // converged to rounding, or a degenerate direction
    const Scalar alpha = Scalar(rz / curvature);
    forEachParticle(n, [&](Index i) {
      deltaV_[i] += alpha * direction_[i];
      residual_[i] -= alpha * product_[i];
    });
    stats_.iterations = iteration;
    const double residualNorm = std::sqrt(dot(residual_, residual_));
    stats_.relativeResidual = residualNorm / rhsNorm;
    if (residualNorm <= tolerance) break;
    forEachParticle(
        n, [&](Index i) { preconditioned_[i] = inverseDiagonal_[i].cwiseProduct(residual_[i]); });
    const double rzNext = dot(residual_, preconditioned_);
    const Scalar beta = Scalar(rzNext / rz);
    rz = rzNext;
    forEachParticle(n, [&](Index i) { direction_[i] = preconditioned_[i] + beta * direction_[i]; });
  }
}

bool ImplicitEuler::step(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
                         SimulationState& state, std::span<Vec3> substepStart) {
  assemble(topology, forces, dt, state);
  solve(topology);
  const Scalar maxSpeedSquared = topology.settings.maxSpeed * topology.settings.maxSpeed;
  const Scalar* inverseMass = topology.inverseMass.data();
  std::atomic<bool> runaway{false};
  forEachParticle(topology.particleCount(), [&](Index i) {
    substepStart[i] = state.position[i];
    if (inverseMass[i] == 0) {
      state.velocity[i].setZero();
      return;
    }
    state.velocity[i] += deltaV_[i];
    state.position[i] += dt * state.velocity[i];
    if (isRunaway(state.velocity[i], maxSpeedSquared))
      runaway.store(true, std::memory_order_relaxed);
  });
  return !runaway.load();
}

}  // namespace softbake
