#pragma once
/// Internal forces of the soft bodies (the paper's §1.1): springs and Matyka–Ollila gas pressure.
/// Each function writes per-spring or per-triangle results into the stage's ForceBuffers; the
/// integrator gathers them per particle.

#include <algorithm>
#include <span>
#include <vector>

#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

/// The force stage's scratch, sized once for a topology: a step allocates nothing.
struct ForceBuffers {
  explicit ForceBuffers(const SceneTopology& topology);

  std::vector<Vec3> springForce;     ///< force on each spring's `a` end
  std::vector<Vec3> triangleForce;   ///< pressure force on each corner of each triangle
  std::vector<double> chunkVolume;   ///< per TriangleChunk
  std::vector<double> bodyVolume;    ///< current enclosed volume per body (rest volume at first)
  std::vector<Scalar> bodyPressure;  ///< current gas pressure per body, Pa
};

/// Hookean force with damping along the axis, on each spring's `a` end (the `b` end gets minus it):
/// f = (k·(|d| − L) + c·(v_b − v_a)·d̂)·d̂ with d = x_b − x_a.
void computeSpringForces(const SceneTopology& topology, const SimulationState& state,
                         ForceBuffers& forces);

/// The force of `spring` on its `a` end, from d = x_b − x_a, |d| > 0 and the velocities: the one
/// formula computeSpringForces() and the implicit step's assembly share.
inline Vec3 springForceOnA(const Spring& spring, const Vec3& d, Scalar length, const Vec3* v) {
  const Vec3 axis = d / length;
  const Scalar stretch = spring.stiffness * (length - spring.restLength);
  const Scalar closing = spring.damping * (v[spring.b] - v[spring.a]).dot(axis);
  return (stretch + closing) * axis;
}

/// Enclosed volume of every closed body by the divergence theorem, V = Σ a·(b×c)/6, summed in
/// double over fixed chunks so the result does not depend on the thread count.
void computeVolumes(const SceneTopology& topology, const SimulationState& state,
                    ForceBuffers& forces);

/// Per triangle, its third of the enclosed volume's gradient: (b − a)×(c − a)/6, a third of its
/// area-weighted normal. A particle's ∂V/∂x is the sum over its triangles, exact for a closed
/// surface. `gradient` has one entry per triangle.
void computeTriangleVolumeGradients(const SceneTopology& topology, std::span<const Vec3> positions,
                                    std::span<Vec3> gradient);

/// P = nRT/V + K·(1 − V/V_rest) per closed body (bodyPressure()), then the force P·A·n̂ of each
/// triangle, a third on each corner. Needs computeVolumes() first.
void computePressureForces(const SceneTopology& topology, const SimulationState& state,
                           ForceBuffers& forces);

/// `force` plus the gas pressure of particle `i`'s triangles, added in the order of its incidence
/// row.
inline Vec3 addPressureForces(const SceneTopology& topology, const ForceBuffers& forces, Index i,
                              Vec3 force) {
  for (Index r = topology.triangleRowStart[i]; r < topology.triangleRowStart[i + 1]; ++r)
    force += forces.triangleForce[topology.triangleRefs[r]];
  return force;
}

/// Every force on particle `i`: gravity, then its springs (the force buffers' spring forces,
/// computeSpringForces()), then its triangles' pressure, summed in the fixed order of its incidence
/// rows (so the sum is the same for any thread count).
inline Vec3 particleForce(const SceneTopology& topology, const ForceBuffers& forces, Index i) {
  Vec3 force = topology.mass[i] * topology.settings.gravity;
  for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
    const Index ref = topology.springRefs[r];
    // The `b` end gets the opposite of the `a` end's force.
    force += (ref & 1) ? Vec3(-forces.springForce[ref >> 1]) : forces.springForce[ref >> 1];
  }
  return addPressureForces(topology, forces, i, force);
}

/// Gravity and gas pressure on particle `i`, without its springs: what the XPBD integrator applies
/// as forces, its springs being constraints. Same fixed order as particleForce().
inline Vec3 gravityAndPressureForce(const SceneTopology& topology, const ForceBuffers& forces,
                                    Index i) {
  return addPressureForces(topology, forces, i, topology.mass[i] * topology.settings.gravity);
}

/// The smallest volume the pressure law is evaluated at, as a fraction of the rest volume: keeps
/// P finite when a body is crushed flat or turned inside out for a moment.
inline constexpr double kMinVolumeFraction = 1e-3;

/// −dP/dV of a body's bulk term, K/V_rest, Pa/m³; 0 for a body without one (open, or a bulk
/// modulus of 0). The implicit step takes this stiffness into its solve, XPBD into its volume push.
inline double bulkStiffness(const Body& body) {
  return body.closed && body.restVolume > 0 && body.material.bulkModulus > 0
             ? double(body.material.bulkModulus) / body.restVolume
             : 0.0;
}

/// A closed body's pressure at `volume`: the gas law's nRT/V, plus the bulk term
/// K·(1 − V/V_rest) (Material::bulkModulus) where the body has one. V is clamped at
/// kMinVolumeFraction of the rest volume for both.
inline double bodyPressure(const Body& body, double volume) {
  volume = std::max(volume, kMinVolumeFraction * body.restVolume);
  const double gas = body.gasAmount > 0 ? body.gasAmount / volume : 0.0;
  const double stiffness = bulkStiffness(body);
  return stiffness > 0 ? gas + stiffness * (body.restVolume - volume) : gas;
}

}  // namespace softbake
