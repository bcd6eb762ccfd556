#pragma once
/// A triangle mesh as it arrives from an importer or a primitive generator: world-space render
/// vertices (split on UV/normal seams the way files store them) and triangles that index them.

#include <string>
#include <vector>

#include "core/types.hpp"

namespace softbake {

struct TriangleMesh {
  std::string name;
  std::vector<Vec3f> positions;  ///< world space, one per render vertex
  std::vector<Vec3f> normals;    ///< per render vertex; empty when the source had none
  std::vector<Vec2f> uvs;        ///< per render vertex; empty when the source had none
  std::vector<Triangle> triangles;  ///< counter-clockwise seen from outside
};

}  // namespace softbake
