#include "importers/ply_import.hpp"

#include <algorithm>

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

// Before anything is allocated for them: the header may lie.
void requireDeclaredWithin(const std::filesystem::path& path, const PlyHeader& header,
                           const ImportLimits& limits) {
  requireWithinLimits(path, declared(header, "vertex"), declared(header, "face"), limits);
  double values = 0;
  for (const PlyElement& element : header.elements)
    values += double(element.count) * double(element.propertyCount);
  requireImportMemory(path, values * kPlyBytesPerValue, "reading the PLY file", limits);
}

// What the data holds against what the header declares, and the strips.
PlyPreparation prepareData(PlyHeader header, std::string_view bytes, const std::string& file) {
  PlyPreparation result;
  result.header = std::move(header);
  const PlyHeader& parsed = result.header;
  const std::string_view data =
      bytes.substr(std::min<std::size_t>(bytes.size(), std::size_t(parsed.dataOffset)));
  const std::vector<std::uint64_t> rows = countPlyRows(parsed, data, file);
  for (std::size_t e = 0; e < parsed.elements.size(); ++e) {
    const PlyElement& element = parsed.elements[e];
    if (rows[e] == element.count) continue;
    const std::string shortfall =
        cat("the header declares ", rowsOf(element, element.count), ", the file holds ", rows[e]);
    if (parsed.format != PlyFormat::kAscii)
      throw Error(cat(file, ": PLY data: ", shortfall, " (truncated file)"));
    result.losses.push_back(shortfall);
  }

  if (hasTriangleStrips(parsed)) {
    PlyStripMesh strips = readPlyStripMesh(parsed, data, file);
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

}  // namespace

PlyPreparation preparePly(const std::filesystem::path& path, const ImportLimits& limits) {
  const std::string file = path.string();
  PlyHeader header = checkPlyFile(path);
  requireDeclaredWithin(path, header, limits);
  const std::string bytes = readWholeFile(file);
  return prepareData(std::move(header), bytes, file);
}

PlyPreparation preparePlyBuffer(std::string_view bytes, const std::string& name,
                                const ImportLimits& limits) {
  PlyHeader header = parsePlyHeader(bytes.substr(0, kMaxPlyHeaderBytes), bytes.size(), name);
  requireDeclaredWithin(name, header, limits);
  return prepareData(std::move(header), bytes, name);
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
