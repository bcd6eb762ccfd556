#pragma once
/// Internal forces of the soft bodies (the paper's §1.1): springs and Matyka–Ollila gas pressure.
/// Each function writes per-spring or per-triangle results into World's scratch arrays; the
/// integrator gathers them per particle.

#include "core/scene/world.hpp"

namespace softbake {

/// Hookean force with damping along the axis, on each spring's `a` end (the `b` end gets minus it):
/// f = (k·(|d| − L) + c·(v_b − v_a)·d̂)·d̂ with d = x_b − x_a.
void computeSpringForces(World& world);

/// Enclosed volume of every closed body by the divergence theorem, V = Σ a·(b×c)/6, summed in
/// double over fixed chunks so the result does not depend on the thread count.
void computeVolumes(World& world);

/// P = nRT/V per closed body, then the force P·A·n̂ of each triangle, a third on each corner.
/// Needs computeVolumes() first.
void computePressureForces(World& world);

/// The smallest volume the pressure law is evaluated at, as a fraction of the rest volume: keeps
/// P finite when a body is crushed flat or turned inside out for a moment.
inline constexpr double kMinVolumeFraction = 1e-3;

}  // namespace softbake
