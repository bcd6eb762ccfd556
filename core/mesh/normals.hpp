#pragma once
/// Smooth per-particle normals of the deformed surface, for exporters and the renderer.

#include <span>
#include <vector>

#include "core/scene/world.hpp"

namespace softbake {

/// Area-weighted average of the adjacent triangles' normals for the particles of `body`, written
/// into `out` (body-local order, resized to the body's particle count). Particles without a usable
/// normal get (0, 1, 0).
void computeSmoothNormals(const World& world, std::span<const Vec3> positions, const Body& body,
                          std::vector<Vec3f>& out);

}  // namespace softbake
