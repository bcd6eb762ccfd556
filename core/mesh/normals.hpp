#pragma once
/// Smooth per-particle normals of the deformed surface, for exporters and the renderer.

#include <span>
#include <vector>

#include "core/types.hpp"

namespace softbake {

/// Area-weighted average of the adjacent triangles' normals for the particles
/// [firstParticle, firstParticle + particleCount), written into `out` in that local order
/// (resized to particleCount). `triangles` index `positions` and use only those particles.
/// Particles without a usable normal get (0, 1, 0).
void computeSmoothNormals(std::span<const Triangle> triangles, std::span<const Vec3> positions,
                          Index firstParticle, Index particleCount, std::vector<Vec3f>& out);

}  // namespace softbake
