#include "core/dynamics/xpbd.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "core/dynamics/for_each_particle.hpp"
#include "core/dynamics/integrator.hpp"

namespace softbake {

namespace {

constexpr std::size_t kConstraintGrain = 1024;

/// Greedy first-fit colouring in spring order: each spring takes the smallest colour that no
/// spring already coloured at either of its ends has. Uses at most 2·(largest degree) − 1 colours,
/// and is the same on every run.
std::vector<int> colourSprings(const SceneTopology& topology) {
  std::vector<int> colour(topology.springs.size(), -1);
  std::vector<std::size_t> takenBy;  // takenBy[c] == s + 1: colour c is taken next to spring s
  for (std::size_t s = 0; s < topology.springs.size(); ++s) {
    for (Index end : {topology.springs[s].a, topology.springs[s].b})
      for (Index r = topology.springRowStart[end]; r < topology.springRowStart[end + 1]; ++r) {
        const int neighbour = colour[topology.springRefs[r] >> 1];
        if (neighbour < 0) continue;
        if (std::size_t(neighbour) >= takenBy.size()) takenBy.resize(std::size_t(neighbour) + 1);
        takenBy[std::size_t(neighbour)] = s + 1;
      }
    std::size_t free = 0;
    while (free < takenBy.size() && takenBy[free] == s + 1) ++free;
    colour[s] = int(free);
  }
  return colour;
}

}  // namespace

Xpbd::Xpbd(const SceneTopology& topology)
    : displacement_(topology.particleCount()),
      triangleGradient_(topology.triangles.size()),
      volumeGradient_(topology.particleCount()),
      gasPush_(topology.bodies.size(), 0.0) {
  const std::vector<int> colour = colourSprings(topology);
  int colours = 0;
  for (int c : colour) colours = std::max(colours, c + 1);
  colourStart_.assign(std::size_t(colours) + 1, 0);
  for (std::size_t s = 0; s < colour.size(); ++s)
    if (topology.springs[s].stiffness > 0) ++colourStart_[std::size_t(colour[s]) + 1];
  for (std::size_t c = 0; c < std::size_t(colours); ++c) colourStart_[c + 1] += colourStart_[c];
  // A spring without stiffness is no constraint (and its damping has nothing to scale by).
  for (Index b = 0; b < topology.bodies.size(); ++b)
    if (topology.bodies[b].closed &&
        (topology.bodies[b].gasAmount > 0 || bulkStiffness(topology.bodies[b]) > 0))
      gasBodies_.push_back(b);
  constraints_.resize(colourStart_.back());
  std::vector<std::size_t> next(colourStart_.begin(), colourStart_.end() - 1);
  for (std::size_t s = 0; s < colour.size(); ++s) {
    const Spring& spring = topology.springs[s];
    if (!(spring.stiffness > 0)) continue;
    constraints_[next[std::size_t(colour[s])]++] = {spring.a, spring.b, spring.restLength,
                                                    1 / spring.stiffness,
                                                    spring.damping / spring.stiffness};
  }
}

void Xpbd::predict(const SceneTopology& topology, Scalar dt, SimulationState& state,
                   std::span<Vec3> substepStart) {
  const Scalar* inverseMass = topology.inverseMass.data();
  const Vec3 gravityStep = dt * topology.settings.gravity;
  const Vec3* x = state.position.data();
  Vec3* v = state.velocity.data();
  Vec3* start = substepStart.data();
  Vec3* displacement = displacement_.data();
  forEachParticle(state.particleCount(), [=](std::size_t i) {
    start[i] = x[i];
    if (inverseMass[i] == 0) {
      v[i].setZero();
      displacement[i].setZero();
    } else {
      displacement[i] = dt * (v[i] + gravityStep);
    }
  });
}

void Xpbd::placeParticles(std::span<const Vec3> substepStart, SimulationState& state) const {
  const Vec3* start = substepStart.data();
  const Vec3* displacement = displacement_.data();
  Vec3* x = state.position.data();
  forEachParticle(state.particleCount(), [=](std::size_t i) { x[i] = start[i] + displacement[i]; });
}

void Xpbd::pushGas(const SceneTopology& topology, Scalar dt, std::span<const Vec3> substepStart,
                   SimulationState& state, ForceBuffers& forces) {
  if (gasBodies_.empty()) return;
  placeParticles(substepStart, state);
  computeVolumes(topology, state, forces);
  computeTriangleVolumeGradients(topology, state.position, triangleGradient_);
  const Vec3* triangleGradient = triangleGradient_.data();
  Vec3* gradient = volumeGradient_.data();
  forEachParticle(state.particleCount(), [&, gradient, triangleGradient](std::size_t i) {
    Vec3 sum = Vec3::Zero();
    for (Index r = topology.triangleRowStart[i]; r < topology.triangleRowStart[i + 1]; ++r)
      sum += triangleGradient[topology.triangleRefs[r]];
    gradient[i] = sum;
  });
  // Per body, the gas as a compliant volume term: one Newton step on inertia plus the gas energy
  // −nRT·ln V along M⁻¹∇V, so the push is P/(1 + h²·(nRT/V²)·Σ w|∇V|²) rather than P: equal to
  // the explicit force at small steps, never overshooting at large ones. The bulk term's energy
  // K/(2·V_rest)·(V − V_rest)² enters the same step, its stiffness K/V_rest beside the gas's: the
  // XPBD volume constraint C = V − V_rest with compliance V_rest/K.
  const double dtSquared = double(dt) * double(dt);
  tbb::parallel_for(std::size_t(0), gasBodies_.size(), [&](std::size_t k) {
    const Index b = gasBodies_[k];
    const Body& body = topology.bodies[b];
    double weightedSquares = 0;
    for (Index i = body.firstParticle; i < body.firstParticle + body.particleCount; ++i)
      weightedSquares += double(topology.inverseMass[i]) * gradient[i].cast<double>().squaredNorm();
    const double volume = std::max(forces.bodyVolume[b], kMinVolumeFraction * body.restVolume);
    const double pressure = bodyPressure(body, volume);
    const double gasStiffness = body.gasAmount / volume / volume;
    const double bulk = bulkStiffness(body);
    const double stiffness = bulk > 0 ? gasStiffness + bulk : gasStiffness;
    gasPush_[b] = pressure / (1 + stiffness * dtSquared * weightedSquares);
    forces.bodyPressure[b] = Scalar(pressure);
  });
  const Index* particleBody = topology.particleBody.data();
  const Scalar* inverseMass = topology.inverseMass.data();
  Vec3* displacement = displacement_.data();
  const double* push = gasPush_.data();
  forEachParticle(state.particleCount(), [=](std::size_t i) {
    displacement[i] += Scalar(dtSquared * push[particleBody[i]]) * inverseMass[i] * gradient[i];
  });
}

void Xpbd::project(const SceneTopology& topology, Scalar dt, std::span<const Vec3> substepStart) {
  const Scalar* inverseMass = topology.inverseMass.data();
  const Vec3* start = substepStart.data();
  Vec3* displacement = displacement_.data();
  const DistanceConstraint* constraints = constraints_.data();
  const Scalar inverseDt = 1 / dt, inverseDtSquared = inverseDt * inverseDt;
  const auto solve = [=](std::size_t k) {
    const DistanceConstraint& c = constraints[k];
    const Scalar wa = inverseMass[c.a], wb = inverseMass[c.b];
    if (wa + wb == 0) return;
    const Vec3 d = (start[c.b] - start[c.a]) + (displacement[c.b] - displacement[c.a]);
    const Scalar length = d.norm();
    // Coincident ends have no direction to push along; the next substep separates them.
    if (!(length > Scalar(1e-12))) return;
    const Vec3 n = d / length;
    const Scalar stretch = length - c.restLength;
    const Scalar compliance = c.compliance * inverseDtSquared;
    const Scalar gamma = c.dampingPerStiffness * inverseDt;
    const Scalar rate = n.dot(displacement[c.b] - displacement[c.a]);
    const Scalar deltaLambda = (-stretch - gamma * rate) / ((1 + gamma) * (wa + wb) + compliance);
    displacement[c.a] -= (wa * deltaLambda) * n;
    displacement[c.b] += (wb * deltaLambda) * n;
  };
  for (std::size_t colour = 0; colour + 1 < colourStart_.size(); ++colour)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(colourStart_[colour],
                                                      colourStart_[colour + 1], kConstraintGrain),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t k = range.begin(); k != range.end(); ++k) solve(k);
                      });
}

bool Xpbd::step(const SceneTopology& topology, ForceBuffers& forces, Scalar dt,
                SimulationState& state, std::span<Vec3> substepStart) {
  predict(topology, dt, state, substepStart);
  pushGas(topology, dt, substepStart, state, forces);
  project(topology, dt, substepStart);
  const Scalar maxSpeedSquared = topology.settings.maxSpeed * topology.settings.maxSpeed;
  const Scalar* inverseMass = topology.inverseMass.data();
  const Scalar inverseDt = 1 / dt;
  Vec3* x = state.position.data();
  Vec3* v = state.velocity.data();
  const Vec3* start = substepStart.data();
  const Vec3* displacement = displacement_.data();
  std::atomic<bool> runaway{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, state.particleCount(), kParticleGrain),
                    [&, x, v, start, displacement](const tbb::blocked_range<std::size_t>& range) {
                      bool chunkRunaway = false;
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        x[i] = start[i] + displacement[i];
                        if (inverseMass[i] == 0) continue;
                        v[i] = displacement[i] * inverseDt;
                        chunkRunaway |= isRunaway(v[i], maxSpeedSquared);
                      }
                      if (chunkRunaway) runaway.store(true, std::memory_order_relaxed);
                    });
  return !runaway.load();
}

}  // namespace softbake
