#pragma once
/// A mesh file's own vertex numbering (the index Blender shows for an OBJ, a PLY's vertex element,
/// a glTF accessor's element), mapped to the vertices softbake imported, so a scene can name
/// vertices the way its user sees them.
///
/// assimp does not keep that numbering for every format: its OBJ reader makes one vertex per face
/// corner, in face order. Where it does not, the file's vertex positions are read here and each is
/// matched to the imported vertex at the same place, which is the one that welds into the particle
/// there.

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace softbake {

/// Where one vertex of the file went.
struct FileVertexPlace {
  static constexpr Index kNone = ~Index(0);
  Index mesh = kNone;  ///< into ImportedMeshes::meshes; kNone when no kept triangle uses the vertex
  Index vertex = 0;    ///< into that mesh's positions
};

struct FileVertices {
  std::vector<FileVertexPlace> places;  ///< per vertex of the file, in the file's order
  std::string unknown;                  ///< why the numbering is not known; empty when it is
};

/// The positions of an OBJ's `v` statements in file order, read as assimp 5.2's OBJ reader reads
/// them (lines joined at a trailing '\', a homogeneous one divided by its w). A statement that
/// reader skips (not 3, 4 or 6 numbers) or cannot read is NaN: it numbers a vertex of the file
/// that no imported vertex is.
std::vector<Vec3f> objVertexPositions(std::string_view text);

/// Vertices softbake imported, in the space of the file's positions.
struct ImportedVertices {
  Index mesh;  ///< the FileVertexPlace::mesh they are
  std::span<const Vec3f> positions;
  std::span<const Triangle> triangles;  ///< only vertices a triangle uses are candidates
};

/// Each of `positions` placed at the nearest candidate within the weld tolerance (kWeldTolerance
/// of the candidates' bounding-box diagonal), the first of `meshes` winning a tie; kNone where
/// there is none.
std::vector<FileVertexPlace> placeByPosition(std::span<const Vec3f> positions,
                                             std::span<const ImportedVertices> meshes);

}  // namespace softbake
