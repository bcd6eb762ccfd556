#include "importers/ply_strips.hpp"

#include <array>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/ply_data.hpp"

namespace softbake {

namespace {

constexpr std::string_view kStrips = "tristrips";

std::optional<std::size_t> findElement(const PlyHeader& header, std::string_view name) {
  for (std::size_t e = 0; e < header.elements.size(); ++e)
    if (header.elements[e].name == name) return e;
  return std::nullopt;
}

std::optional<std::size_t> findScalar(const PlyElement& element, std::string_view name) {
  for (std::size_t p = 0; p < element.properties.size(); ++p)
    if (!element.properties[p].list && element.properties[p].name == name) return p;
  return std::nullopt;
}

bool isInteger(PlyScalar type) {
  return type != PlyScalar::kFloat32 && type != PlyScalar::kFloat64;
}

// The list of vertex indices of a face or strip element: by its usual names, else (as assimp
// does for strips) the element's only list.
std::optional<std::size_t> findIndexList(const PlyElement& element) {
  std::optional<std::size_t> onlyList;
  std::size_t lists = 0;
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& property = element.properties[p];
    if (!property.list) continue;
    if (property.name == "vertex_indices" || property.name == "vertex_index") return p;
    ++lists;
    onlyList = p;
  }
  return lists == 1 ? onlyList : std::nullopt;
}

// Where a vertex row keeps what the mesh needs.
struct VertexLayout {
  std::array<std::size_t, 3> position{};
  std::optional<std::array<std::size_t, 3>> normal;
  std::optional<std::array<std::size_t, 2>> uv;
};

VertexLayout vertexLayout(const PlyElement& vertex, std::string_view source) {
  VertexLayout layout;
  const auto scalars = [&](
      auto... names) -> std::optional<std::array<std::size_t, sizeof...(names)>> {
    std::array<std::optional<std::size_t>, sizeof...(names)> found = {findScalar(vertex, names)...};
    std::array<std::size_t, sizeof...(names)> indices{};
    for (std::size_t i = 0; i < found.size(); ++i) {
      if (!found[i]) return std::nullopt;
      indices[i] = *found[i];
    }
    return indices;
  };
  const auto position = scalars("x", "y", "z");
  if (!position)
    throw Error(cat(source, ": PLY element 'vertex' has no x, y and z properties: no positions"));
  layout.position = *position;
  layout.normal = scalars("nx", "ny", "nz");
  constexpr std::array<std::pair<const char*, const char*>, 3> kUvNames = {
      {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}}};
  for (const auto& [u, v] : kUvNames)
    if (!layout.uv) layout.uv = scalars(u, v);
  return layout;
}

void requireIntegerList(const PlyElement& element, std::optional<std::size_t> list,
                        std::string_view source) {
  if (!list)
    throw Error(cat(source, ": PLY element '", element.name,
                    "' has no list of vertex indices (vertex_indices): cannot read its ",
                    element.name == kStrips ? "triangle strips" : "faces"));
  const PlyProperty& property = element.properties[*list];
  if (!isInteger(property.type))
    throw Error(cat(source, ": PLY element '", element.name, "': list '", property.name,
                    "' holds non-integer vertex indices: cannot read its ",
                    element.name == kStrips ? "triangle strips" : "faces"));
}

bool validIndex(double index, std::uint64_t vertexCount) {
  return index >= 0 && index < double(vertexCount);
}

}  // namespace

bool hasTriangleStrips(const PlyHeader& header) {
  const std::optional<std::size_t> strips = findElement(header, kStrips);
  return strips && header.elements[*strips].count > 0;
}

std::size_t appendStripTriangles(std::span<const double> indices, std::uint64_t vertexCount,
                                 std::vector<Triangle>& triangles) {
  std::size_t invalid = 0;
  std::size_t start = 0;  // of the current strip in `indices`
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] == -1) {
      start = i + 1;
      continue;
    }
    if (i < start + 2) continue;
    double a = indices[i - 2], b = indices[i - 1];
    const double c = indices[i];
    // Odd triangles of a strip run the other way round; swapping two corners restores them.
    if ((i - start) % 2 == 1) std::swap(a, b);
    if (a == b || b == c || a == c) continue;
    if (!validIndex(a, vertexCount) || !validIndex(b, vertexCount) || !validIndex(c, vertexCount)) {
      ++invalid;
      continue;
    }
    triangles.push_back({Index(a), Index(b), Index(c)});
  }
  return invalid;
}

PlyStripMesh readPlyStripMesh(const PlyHeader& header, std::string_view data,
                              std::string_view source) {
  const std::optional<std::size_t> vertexElement = findElement(header, "vertex");
  if (!vertexElement) throw Error(cat(source, ": PLY file has no 'vertex' element"));
  const VertexLayout layout = vertexLayout(header.elements[*vertexElement], source);
  const std::optional<std::size_t> stripElement = findElement(header, kStrips);
  const std::optional<std::size_t> faceElement = findElement(header, "face");
  std::optional<std::size_t> stripList, faceList;
  if (stripElement) {
    stripList = findIndexList(header.elements[*stripElement]);
    requireIntegerList(header.elements[*stripElement], stripList, source);
  }
  if (faceElement && header.elements[*faceElement].count > 0) {
    faceList = findIndexList(header.elements[*faceElement]);
    requireIntegerList(header.elements[*faceElement], faceList, source);
  }

  PlyStripMesh result;
  TriangleMesh& mesh = result.mesh;
  std::vector<double> strips;  // every row's strips, rows separated by -1
  std::vector<double> faceIndices;
  std::vector<std::size_t> faceSizes;
  readPlyRows(header, data, source, [&](std::size_t element, std::uint64_t, const PlyRow& row) {
    if (element == vertexElement) {
      const auto& [x, y, z] = layout.position;
      mesh.positions.emplace_back(float(row.scalars[x]), float(row.scalars[y]),
                                  float(row.scalars[z]));
      if (layout.normal) {
        const auto& [nx, ny, nz] = *layout.normal;
        mesh.normals.emplace_back(float(row.scalars[nx]), float(row.scalars[ny]),
                                  float(row.scalars[nz]));
      }
      if (layout.uv) {
        const auto& [u, v] = *layout.uv;
        mesh.uvs.emplace_back(float(row.scalars[u]), float(row.scalars[v]));
      }
    } else if (element == stripElement) {
      const std::vector<double>& list = row.lists[*stripList];
      strips.insert(strips.end(), list.begin(), list.end());
      strips.push_back(-1);
    } else if (element == faceElement) {
      const std::vector<double>& list = row.lists[*faceList];
      faceIndices.insert(faceIndices.end(), list.begin(), list.end());
      faceSizes.push_back(list.size());
    }
  });

  const std::uint64_t vertices = mesh.positions.size();
  std::size_t invalidFaces = 0, skippedFaces = 0;
  std::size_t offset = 0;
  for (const std::size_t size : faceSizes) {
    const std::span<const double> face(faceIndices.data() + offset, size);
    offset += size;
    if (size < 3) {
      ++skippedFaces;
      continue;
    }
    bool valid = true;
    for (double index : face) valid &= validIndex(index, vertices);
    if (!valid) {
      ++invalidFaces;
      continue;
    }
    for (std::size_t k = 1; k + 1 < size; ++k)
      mesh.triangles.push_back({Index(face[0]), Index(face[k]), Index(face[k + 1])});
  }
  const std::size_t fromFaces = mesh.triangles.size();
  const std::size_t invalidStrips = appendStripTriangles(strips, vertices, mesh.triangles);
  result.stripTriangles = mesh.triangles.size() - fromFaces;

  if (invalidStrips > 0)
    result.losses.push_back(
        cat(invalidStrips, " strip triangles dropped (vertex index out of range)"));
  if (invalidFaces > 0)
    result.losses.push_back(cat(invalidFaces, " faces dropped (vertex index out of range)"));
  result.pointsAndLines = skippedFaces;
  return result;
}

}  // namespace softbake
