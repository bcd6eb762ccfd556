#pragma once
/// The time-step bound of explicit (symplectic) Euler for the scene's spring network.
///
/// For one mode x'' = −ω²x − γx', the step v += h·a, x += h·v is stable when h²ω² + 2hγ < 4
/// (the Jury conditions on its 2×2 amplification matrix). The stiffest mode of the whole network is
/// bounded per particle by Gershgorin's theorem on M⁻¹K: ω² ≤ 2·Σk/m and likewise γ ≤ 2·Σc/m over
/// the particle's springs. Solving for h gives h < (√(γ² + 4ω²) − γ)/ω². Gas pressure and contacts
/// add much softer modes and are left out; the safety factor covers them. A body's bulk term
/// (Material::bulkModulus) can be stiff, so its one mode is added to its particles' ω².

#include <cstdint>
#include <span>
#include <vector>

#include "core/scene/scene_topology.hpp"

namespace softbake {

struct StabilityBound {
  double maxTimeStep = 0;      ///< seconds; infinity when nothing in the scene is a spring
  Index limitingParticle = 0;  ///< the particle whose springs set the bound
};

StabilityBound computeStabilityBound(const SceneTopology& topology);

/// Fraction of the bound that "auto" substeps aim for.
inline constexpr double kStabilitySafety = 0.8;

struct SubstepChoice {
  int substeps = 1;
  bool automatic = false;
  double timeStep = 0;            ///< seconds per substep
  double boundTimeStep = 0;       ///< the stability bound, seconds
  int minimumStableSubsteps = 1;  ///< fewest substeps that keep the time step under the bound
  /// The implicit and XPBD integrators: stable at any step, so the bound does not apply, and
  /// "auto" is chosen by contactAccuracySubsteps() every frame (for XPBD, never below
  /// minimumStableSubsteps, which keeps its springs' stiffness).
  bool stableAtAnyStep = false;
  /// Under "auto" of those integrators: the closing speed that set the count, m/s (0: no two
  /// surfaces can meet within the frame, so the count is the floor, kMinAutoSubsteps).
  double closingSpeed = 0;
  bool belowBound() const { return !stableAtAnyStep && substeps < minimumStableSubsteps; }
};

/// `requested` 0 means automatic: enough substeps to stay under kStabilitySafety of the bound.
SubstepChoice chooseSubsteps(const SceneTopology& topology, int requested);

}  // namespace softbake
