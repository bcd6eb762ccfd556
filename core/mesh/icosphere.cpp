#include "core/mesh/icosphere.hpp"

#include <cmath>
#include <algorithm>
#include <map>
#include <numbers>

namespace softbake {

TriangleMesh makeIcosphere(int subdivisions, float radius, const Vec3f& center) {
  const float phi = float(std::numbers::phi);
  std::vector<Vec3f> unit = {{-1, phi, 0}, {1, phi, 0},  {-1, -phi, 0}, {1, -phi, 0},
                             {0, -1, phi}, {0, 1, phi},  {0, -1, -phi}, {0, 1, -phi},
                             {phi, 0, -1}, {phi, 0, 1},  {-phi, 0, -1}, {-phi, 0, 1}};
  for (Vec3f& p : unit) p.normalize();
  std::vector<Triangle> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<Index, Index>, Index> midpoints;
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      auto [it, inserted] = midpoints.try_emplace({key.first, key.second}, Index(unit.size()));
      if (inserted) unit.push_back((unit[a] + unit[b]).normalized());
      return it->second;
    };
    std::vector<Triangle> finer;
    finer.reserve(faces.size() * 4);
    for (const Triangle& f : faces) {
      const Index ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    faces = std::move(finer);
  }
  TriangleMesh mesh;
  mesh.name = "icosphere";
  mesh.triangles = std::move(faces);
  for (const Vec3f& p : unit) {
    mesh.positions.push_back(center + radius * p);
    mesh.normals.push_back(p);
    // Equirectangular UVs so textures and the OBJ export have coordinates to carry.
    mesh.uvs.emplace_back(0.5f + std::atan2(p.z(), p.x()) / (2 * std::numbers::pi_v<float>),
                          0.5f + std::asin(std::clamp(p.y(), -1.f, 1.f)) / std::numbers::pi_v<float>);
  }
  return mesh;
}

}  // namespace softbake
