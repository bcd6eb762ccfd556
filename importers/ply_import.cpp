#include "importers/ply_import.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/ply_data.hpp"
#include "importers/ply_strips.hpp"

namespace softbake {

namespace {

// assimp 5.2's PLY reader keeps every value of every row in its own std::vector of 4-byte values.
constexpr double kPlyBytesPerValue = sizeof(std::vector<float>) + 4;

std::string rowsOf(const PlyElement& element, std::uint64_t rows) {
  if (element.name == "vertex") return cat(rows, rows == 1 ? " vertex" : " vertices");
  if (element.name == "face") return cat(rows, rows == 1 ? " face" : " faces");
  return cat(rows, " '", element.name, "' rows");
}

std::uint64_t declared(const PlyHeader& header, std::string_view name) {
  for (const PlyElement& element : header.elements)
    if (element.name == name) return element.count;
  return 0;
}

}  // namespace

PlyPreparation preparePly(const std::filesystem::path& path, const ImportLimits& limits) {
  const std::string file = path.string();
  PlyPreparation result;
  result.header = checkPlyFile(path);
  const PlyHeader& header = result.header;
  // Before anything is allocated for them: the header may lie.
  requireWithinLimits(path, declared(header, "vertex"), declared(header, "face"), limits);
  double values = 0;
  for (const PlyElement& element : header.elements)
    values += double(element.count) * double(element.propertyCount);
  requireImportMemory(path, values * kPlyBytesPerValue, "reading the PLY file", limits);

  const std::string bytes = readWholeFile(file);
  const std::string_view data = std::string_view(bytes).substr(
      std::min<std::size_t>(bytes.size(), std::size_t(header.dataOffset)));
  const std::vector<std::uint64_t> rows = countPlyRows(header, data, file);
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    if (rows[e] == element.count) continue;
    const std::string shortfall =
        cat("the header declares ", rowsOf(element, element.count), ", the file holds ", rows[e]);
    if (header.format != PlyFormat::kAscii)
      throw Error(cat(file, ": PLY data: ", shortfall, " (truncated file)"));
    result.losses.push_back(shortfall);
  }

  if (hasTriangleStrips(header)) {
    PlyStripMesh strips = readPlyStripMesh(header, data, file);
    for (std::string& loss : strips.losses) result.losses.push_back(std::move(loss));
    result.notes.push_back(cat(file, ": read ", strips.stripTriangles,
                               " triangles from its triangle strips (assimp 5.2 reads one)"));
    if (strips.pointsAndLines > 0)
      result.notes.push_back(cat(file, ": ignored ", strips.pointsAndLines,
                                 " faces of fewer than 3 corners (only triangles are simulated)"));
    result.mesh = std::move(strips.mesh);
  }
  return result;
}

void compareWithHeader(const PlyHeader& header, std::size_t vertices, std::size_t faces,
                       std::vector<std::string>& losses) {
  const std::uint64_t declaredVertices = declared(header, "vertex");
  const std::uint64_t declaredFaces = declared(header, "face");
  if (vertices < declaredVertices)
    losses.push_back(cat("assimp read ", vertices, " of the ", declaredVertices,
                         " vertices the header declares"));
  if (faces < declaredFaces)
    losses.push_back(
        cat("assimp read ", faces, " of the ", declaredFaces, " faces the header declares"));
}

}  // namespace softbake
