#pragma once
/// Extended position-based dynamics with small steps (Macklin, Müller & Chentanez, "XPBD:
/// Position-Based Simulation of Compliant Constrained Dynamics", 2016; Macklin et al., "Small
/// Steps in Physics Simulation", 2019): the second stable integrator, as in Houdini's Vellum and
/// Jolt's soft bodies.
///
/// One substep of h seconds works on the displacement Δ = x − x₀:
///   1. Δ ← h·(v + h·g)  (inertia and gravity);
///   2. the gas as a compliant volume term: per closed body, Δ ← Δ + h²·w·p·∂V/∂x with
///      p = P/(1 + h²·(nRT/V²)·Σ w|∂V/∂x|²), one Newton step on the gas energy −nRT·ln V: the
///      explicit pressure force at small steps, never overshooting at large ones; a body's bulk
///      term (Material::bulkModulus) is a compliant volume constraint C = V − V_rest of
///      compliance V_rest/K in the same step, its stiffness added to the gas's;
///   3. one Gauss–Seidel sweep over every spring as a distance constraint C = |x_b − x_a| − L with
///      compliance α = 1/k and Rayleigh damping β = c, so stiffness keeps N/m and damping N·s/m:
///        α̃ = α/h²,  γ = α̃·h²·β/h = c/(k·h),
///        Δλ = (−C − γ·∇C·Δ) / ((1 + γ)(w_a + w_b) + α̃)   (λ starts at zero: one sweep);
///   4. x ← x₀ + Δ, v ← Δ/h.
/// Δ rather than x carries the corrections: a correction of k·h²·C is far below the float spacing
/// of a position at small steps and would round away. Then the collision pipeline sees each
/// particle's segment x₀ → x, as under the other integrators.
///
/// Stable at any step: a constraint can at most be satisfied, never overshoot. The price is
/// stiffness. With one sweep and λ from zero, a spring pulls with k/(1 + w·k·h²), not k, and the
/// sweep pulls a pressurised body's inflation back by only about (edge/radius)² per substep, so at
/// few substeps bodies are softer and rounder balls swell. Holding the presets' meaning (a resting
/// ball's volume within 5% of explicit Euler's) took as many substeps as explicit Euler's
/// stability bound, and twice that for the balloon preset (bench/results/integrators.md). "auto"
/// substeps therefore never go below that bound; fewer, given explicitly, stay stable and soften.
///
/// Deterministic and parallel: the springs are graph-coloured once (greedy, in spring order) so
/// that no two springs of one colour share a particle. Colours run in order, the springs of one
/// colour in parallel, and each writes only its own two particles, so the result is the same for
/// any thread count. Every buffer is sized at construction: a step allocates nothing.

#include <cstddef>
#include <span>
#include <vector>

#include "core/dynamics/forces.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

class Xpbd {
 public:
  explicit Xpbd(const SceneTopology& topology);

  /// One substep of `dt` seconds. `forces` is scratch for the volumes, and keeps each body's
  /// latest volume and pressure; its spring and triangle forces are not used. `substepStart`
  /// receives the positions at the start. Returns false when some particle's velocity is not
  /// finite or exceeds settings.maxSpeed.
  bool step(const SceneTopology& topology, ForceBuffers& forces, Scalar dt, SimulationState& state,
            std::span<Vec3> substepStart);

  /// Springs of colour c are constraints [colourStart()[c], colourStart()[c + 1]).
  std::span<const std::size_t> colourStart() const { return colourStart_; }

  /// A spring as the solver reads it, in colour order.
  struct DistanceConstraint {
    Index a, b;
    Scalar restLength;
    Scalar compliance;           ///< 1/k, m/N
    Scalar dampingPerStiffness;  ///< c/k, seconds
  };
  std::span<const DistanceConstraint> constraints() const { return constraints_; }

 private:
  void predict(const SceneTopology& topology, Scalar dt, SimulationState& state,
               std::span<Vec3> substepStart);
  /// x ← x₀ + Δ, for the stages that need positions (volumes, gradients).
  void placeParticles(std::span<const Vec3> substepStart, SimulationState& state) const;
  void pushGas(const SceneTopology& topology, Scalar dt, std::span<const Vec3> substepStart,
               SimulationState& state, ForceBuffers& forces);
  void project(const SceneTopology& topology, Scalar dt, std::span<const Vec3> substepStart);

  std::vector<DistanceConstraint> constraints_;
  std::vector<std::size_t> colourStart_;
  std::vector<Index> gasBodies_;        ///< closed bodies with gas
  std::vector<Vec3> displacement_;      ///< Δ = x − x₀ of the substep, per particle
  std::vector<Vec3> triangleGradient_;  ///< per triangle, its share of each corner's ∂V/∂x
  std::vector<Vec3> volumeGradient_;    ///< ∂V/∂x per particle
  std::vector<double> gasPush_;         ///< per body: the pressure the substep applies, Pa
};

}  // namespace softbake
