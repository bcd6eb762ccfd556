#pragma once
/// A sphere of any face count: each face of a cube cut into divisions × divisions squares of two
/// triangles, 12·divisions² in all, every vertex pushed out onto the sphere. The icosphere only
/// comes in steps of 4×; benchmarks and scaling runs need 1k, 10k, 100k and 1M faces.
/// Shared vertices (6·d² + 2), outward winding, no seams.

#include <cstddef>

#include "core/mesh/triangle_mesh.hpp"

namespace softbake {

TriangleMesh makeCubeSphere(int divisions, float radius, const Vec3f& center = Vec3f::Zero());

/// The divisions whose cube sphere has the face count nearest to `faces` (at least 1).
int cubeSphereDivisions(std::size_t faces);

}  // namespace softbake
