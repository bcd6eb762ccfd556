#pragma once
/// Reading triangle meshes from any file assimp reads.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/triangle_mesh.hpp"
#include "importers/file_vertices.hpp"
#include "importers/import_limits.hpp"

namespace softbake {

struct MeshImportOptions {
  /// Merge every mesh of the file into one (one body); otherwise one mesh per aiMesh instance.
  bool mergeMeshes = false;
  /// Import what is left of a file that lost geometry on the way (import_losses.hpp), with a
  /// warning, instead of refusing it.
  bool acceptLossy = false;
  ImportLimits limits{};
  /// Work out ImportedMeshes::fileVertices; an OBJ is read a second time for it.
  bool numberFileVertices = false;
};

struct ImportedMeshes {
  /// World space (node transforms applied, winding flipped under mirroring transforms),
  /// triangles only. Named after the node, or the aiMesh, or the file.
  std::vector<TriangleMesh> meshes;
  std::vector<std::string> notes;  ///< things the user should hear about, one line each
  /// Things that may be wrong with the result: assimp's warnings and errors ("x.gltf: assimp:
  /// …"), an accepted loss. One line each, starting with the file.
  std::vector<std::string> warnings;
  /// With MeshImportOptions::numberFileVertices, where each vertex of the file went, numbered as
  /// the file numbers them: an OBJ's `v` statements, a PLY's or OFF's vertex list, an STL's facet
  /// corners (three per facet), a glTF's POSITION accessor elements, one primitive after another
  /// (the `pins` section of docs/scene_format.md). Other formats leave it unknown.
  FileVertices fileVertices;
};

/// Throws softbake::Error, naming the file, when it is missing, not a format assimp reads,
/// malformed (including PLY headers that would crash assimp 5.2), has no triangles, has
/// non-finite coordinates, lost geometry on the way (unless options.acceptLossy), or is above
/// options.limits or too large for this machine's memory.
ImportedMeshes importMeshFile(const std::filesystem::path& path,
                              const MeshImportOptions& options = {});

/// The same for a file already in memory (the fuzz targets feed it bytes). `name` names it in
/// messages, and its extension tells assimp the format, which an OBJ's content does not. Only
/// `bytes` is read: companion files (an OBJ's .mtl, a glTF's .bin) are not looked for, so a file
/// that needs one fails as if it were missing.
ImportedMeshes importMeshBuffer(std::string_view bytes, const std::string& name,
                                const MeshImportOptions& options = {});

}  // namespace softbake
