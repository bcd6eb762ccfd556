#pragma once
/// The built-in sphere: an icosahedron subdivided `subdivisions` times and projected onto the
/// sphere (level 3: 642 vertices, 1280 triangles). Shared vertices, outward winding, no seams.

#include "core/mesh/triangle_mesh.hpp"

namespace softbake {

TriangleMesh makeIcosphere(int subdivisions, float radius, const Vec3f& center = Vec3f::Zero());

}  // namespace softbake
