#pragma once
/// One frame of an OBJ sequence read back for `softbake compare`: its objects (`o` lines, softbake
/// writes one per body), their vertices and triangles. Polygons become triangle fans; normals,
/// UVs and materials are not read.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace softbake {

struct ObjObject {
  std::string name;
  std::size_t firstVertex = 0, vertexCount = 0;         ///< a range of ObjFrame::positions
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< indices within the object
};

struct ObjFrame {
  std::vector<Vec3f> positions;
  std::vector<ObjObject> objects;
};

/// Reads an OBJ file. Vertices before any `o` line belong to an object named after the file.
/// Throws softbake::Error naming the file and line: a bad number, a face index out of range or
/// into another object's vertices.
ObjFrame readObjFrame(const std::filesystem::path& path);

}  // namespace softbake
