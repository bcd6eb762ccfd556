#include "core/mesh/cube_sphere.hpp"

#include <array>
#include <cmath>
#include <map>

namespace softbake {

TriangleMesh makeCubeSphere(int divisions, float radius, const Vec3f& center) {
  const int d = std::max(1, divisions);
  TriangleMesh mesh;
  mesh.name = "cube_sphere";
  // Vertices are keyed by their integer lattice point on the cube's surface, so the cube's edges
  // and corners, reached from two or three faces, become one vertex.
  std::map<std::array<int, 3>, Index> index;
  const auto vertex = [&](std::array<int, 3> lattice) {
    const auto [it, inserted] = index.try_emplace(lattice, Index(mesh.positions.size()));
    if (inserted) {
      // Spacing by tangent spreads the vertices more evenly than a plain projection does.
      Vec3f p;
      for (int axis = 0; axis < 3; ++axis)
        p[axis] = std::tan(0.25f * 3.14159265f * (2.0f * float(lattice[axis]) / float(d) - 1.0f));
      p.normalize();
      mesh.positions.push_back(center + radius * p);
      mesh.normals.push_back(p);
    }
    return it->second;
  };
  // Each face: the fixed axis and its side, and two in-face axes ordered so u × v points out.
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + (side ? 1 : 2)) % 3, v = (axis + (side ? 2 : 1)) % 3;
      for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) {
          std::array<Index, 4> corner;
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> lattice{};
            lattice[axis] = side * d;
            lattice[u] = i + (k == 1 || k == 2);
            lattice[v] = j + (k >= 2);
            corner[k] = vertex(lattice);
          }
          mesh.triangles.push_back({corner[0], corner[1], corner[2]});
          mesh.triangles.push_back({corner[0], corner[2], corner[3]});
        }
    }
  return mesh;
}

int cubeSphereDivisions(std::size_t faces) {
  return std::max(1, int(std::lround(std::sqrt(double(faces) / 12.0))));
}

}  // namespace softbake
