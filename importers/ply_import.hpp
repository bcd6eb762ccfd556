#pragma once
/// What softbake does with a PLY file before and instead of assimp: the header check
/// (ply_guard.hpp), the rows the data really holds (ply_data.hpp), and triangle strips, which it
/// reads itself (ply_strips.hpp).

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/triangle_mesh.hpp"
#include "importers/import_limits.hpp"
#include "importers/ply_guard.hpp"

namespace softbake {

struct PlyPreparation {
  PlyHeader header;
  /// Geometry the file lacks: "the header declares 12 faces, the file holds 6".
  std::vector<std::string> losses;
  /// The file's mesh when softbake read it itself (its faces are triangle strips); otherwise
  /// assimp reads it.
  std::optional<TriangleMesh> mesh;
  std::vector<std::string> notes;
};

/// Checks the header, its counts against `limits`, the memory assimp would need for it and the
/// rows the data holds. Throws softbake::Error naming the file for a bad header, counts above the
/// limits, a binary file cut short (assimp 5.2 would
/// read past its end), or strips it cannot read; an ascii file cut short is a loss, since assimp
/// pads it with copies of its last row.
PlyPreparation preparePly(const std::filesystem::path& path, const ImportLimits& limits);

/// The same for a file already in memory, `name` naming it in messages.
PlyPreparation preparePlyBuffer(std::string_view bytes, const std::string& name,
                                const ImportLimits& limits);

/// Adds a loss when assimp's scene, before post-processing, has fewer vertices or faces than the
/// header declares.
void compareWithHeader(const PlyHeader& header, std::size_t vertices, std::size_t faces,
                       std::vector<std::string>& losses);

}  // namespace softbake
