#include "core/mesh/normals.hpp"

#include <cmath>

namespace softbake {

void computeSmoothNormals(std::span<const Triangle> triangles, std::span<const Vec3> positions,
                          Index firstParticle, Index particleCount, std::vector<Vec3f>& out) {
  out.assign(particleCount, Vec3f::Zero());
  for (const Triangle& tri : triangles) {
    // The cross product's length is twice the area: larger triangles weigh more.
    const Vec3f n = (positions[tri[1]] - positions[tri[0]])
                        .cross(positions[tri[2]] - positions[tri[0]])
                        .template cast<float>();
    for (Index v : tri) out[v - firstParticle] += n;
  }
  for (Vec3f& n : out) {
    const float length = n.norm();
    n = length > 0 && std::isfinite(length) ? Vec3f(n / length) : Vec3f::UnitY();
  }
}

}  // namespace softbake
