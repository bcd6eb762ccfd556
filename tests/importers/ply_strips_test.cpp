// PLY triangle strips, which assimp 5.2 reads as one triangle: softbake reads them itself, in
// ascii and both binary byte orders, with the strips' alternating winding.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <utility>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/mesh_import.hpp"
#include "importers/ply_strips.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// A unit sphere of `rings` latitude bands and `segments` longitudes, stored as one triangle strip
// per band: poles alternate with their ring, which makes every other triangle degenerate, as
// strip files do. Wound outward.
struct StripSphere {
  std::vector<std::array<float, 3>> positions;
  std::vector<std::vector<int>> strips;

  StripSphere(int rings, int segments) {
    positions.push_back({0, 1, 0});
    for (int k = 1; k < rings; ++k) {
      const double theta = std::numbers::pi * k / rings;
      for (int j = 0; j < segments; ++j) {
        const double phi = 2 * std::numbers::pi * j / segments;
        positions.push_back({float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                             float(-std::sin(theta) * std::sin(phi))});
      }
    }
    const int bottom = int(positions.size());
    positions.push_back({0, -1, 0});
    const auto ring = [&](int k, int j) { return 1 + (k - 1) * segments + j % segments; };
    for (int band = 0; band < rings; ++band) {
      std::vector<int> strip;
      for (int j = 0; j <= segments; ++j) {
        strip.push_back(band == 0 ? 0 : ring(band, j));
        strip.push_back(band == rings - 1 ? bottom : ring(band + 1, j));
      }
      strips.push_back(std::move(strip));
    }
  }
};

template <class T>
void appendBinary(std::string& out, T value, bool bigEndian) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (bigEndian != (std::endian::native == std::endian::big))
    std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

// `oneRow`: every strip in one row, separated by -1 (as the cow model stores them); otherwise a
// row per strip.
std::string stripPly(const StripSphere& sphere, PlyFormat format, bool oneRow) {
  std::vector<std::vector<int>> rows;
  if (oneRow) {
    rows.emplace_back();
    for (const std::vector<int>& strip : sphere.strips) {
      if (!rows[0].empty()) rows[0].push_back(-1);
      rows[0].insert(rows[0].end(), strip.begin(), strip.end());
    }
  } else {
    rows = sphere.strips;
  }
  const char* formatName = format == PlyFormat::kAscii                ? "ascii"
                           : format == PlyFormat::kBinaryLittleEndian ? "binary_little_endian"
                                                                      : "binary_big_endian";
  std::string text = cat("ply\nformat ", formatName, " 1.0\ncomment strips test\nelement vertex ",
                         sphere.positions.size(),
                         "\nproperty float x\nproperty float y\nproperty float z\n"
                         "element tristrips ",
                         rows.size(), "\nproperty list int int vertex_indices\nend_header\n");
  const bool big = format == PlyFormat::kBinaryBigEndian;
  for (const auto& p : sphere.positions) {
    if (format == PlyFormat::kAscii) {
      text += cat(p[0], " ", p[1], " ", p[2], "\n");
    } else {
      for (float x : p) appendBinary(text, x, big);
    }
  }
  for (const std::vector<int>& row : rows) {
    if (format == PlyFormat::kAscii) {
      text += cat(row.size());
      for (int index : row) text += cat(" ", index);
      text += "\n";
    } else {
      appendBinary(text, std::int32_t(row.size()), big);
      for (int index : row) appendBinary(text, std::int32_t(index), big);
    }
  }
  return text;
}

// Every edge of a closed, consistently wound surface is walked once each way.
bool isClosedAndConsistentlyWound(const std::vector<Triangle>& triangles) {
  std::map<std::pair<Index, Index>, int> directed;
  for (const Triangle& t : triangles)
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) return false;
  }
  return true;
}

double meshSignedVolume(const TriangleMesh& mesh) {
  double volume = 0;
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[t[2]].cast<double>();
    volume += a.dot(b.cross(c)) / 6;
  }
  return volume;
}

using test::importError;

TEST(PlyStrips, AlternateTheWindingAndSkipTheDegenerateJoins) {
  std::vector<Triangle> triangles;
  const std::vector<double> indices = {0, 1, 2, 3, 4, -1, 5, 6, 7, 7, 8, 9};
  EXPECT_EQ(appendStripTriangles(indices, 10, triangles), 0u);
  // 0 1 2 | 2 1 3 (odd: swapped) | 2 3 4; then a new strip: 5 6 7, two joins, 8 7 9 (odd).
  EXPECT_THAT(triangles, ElementsAre(Triangle{0, 1, 2}, Triangle{2, 1, 3}, Triangle{2, 3, 4},
                                     Triangle{5, 6, 7}, Triangle{8, 7, 9}));
}

TEST(PlyStrips, CountTrianglesWithIndicesOutOfRange) {
  std::vector<Triangle> triangles;
  const std::vector<double> indices = {0, 1, 2, 3, -2, 4};
  // Three vertices: every triangle that touches 3, -2 or 4 is out.
  EXPECT_EQ(appendStripTriangles(indices, 3, triangles), 3u);
  EXPECT_THAT(triangles, ElementsAre(Triangle{0, 1, 2}));
}

class PlyStripFile : public ::testing::TestWithParam<std::pair<PlyFormat, bool>> {};

TEST_P(PlyStripFile, LoadsEveryTriangleAsAClosedOutwardSurface) {
  const auto [format, oneRow] = GetParam();
  const StripSphere sphere(8, 12);
  test::ScratchDir dir;
  const auto file = dir.write("sphere_strips.ply", stripPly(sphere, format, oneRow));
  const ImportedMeshes imported = importMeshFile(file);
  ASSERT_EQ(imported.meshes.size(), 1u);
  const TriangleMesh& mesh = imported.meshes[0];
  // 12 per polar band, 24 per each of the 6 others.
  EXPECT_EQ(mesh.triangles.size(), 2u * 12 * 7);
  EXPECT_EQ(mesh.positions.size(), sphere.positions.size());
  EXPECT_TRUE(isClosedAndConsistentlyWound(mesh.triangles));
  // Outward: positive, and near the unit sphere's 4.19 (the polyhedron is a little smaller).
  EXPECT_GT(meshSignedVolume(mesh), 3.5);
  EXPECT_LT(meshSignedVolume(mesh), 4.19);
  EXPECT_THAT(imported.notes,
              ElementsAre(file.string() + ": read 168 triangles from its "
                                          "triangle strips (assimp 5.2 reads one)"));
  EXPECT_THAT(imported.warnings, ::testing::IsEmpty());
}

INSTANTIATE_TEST_SUITE_P(AsciiAndBothByteOrders, PlyStripFile,
                         ::testing::Values(std::pair{PlyFormat::kAscii, true},
                                           std::pair{PlyFormat::kAscii, false},
                                           std::pair{PlyFormat::kBinaryLittleEndian, true},
                                           std::pair{PlyFormat::kBinaryLittleEndian, false},
                                           std::pair{PlyFormat::kBinaryBigEndian, true},
                                           std::pair{PlyFormat::kBinaryBigEndian, false}),
                         [](const ::testing::TestParamInfo<std::pair<PlyFormat, bool>>& param) {
                           return cat(param.param.first == PlyFormat::kAscii ? "Ascii"
                                      : param.param.first == PlyFormat::kBinaryLittleEndian
                                          ? "LittleEndian"
                                          : "BigEndian",
                                      param.param.second ? "OneRowOfStrips" : "ARowPerStrip");
                         });

TEST(PlyStrips, AnIndexPastTheVerticesIsALossNamingTheFile) {
  StripSphere sphere(4, 6);
  sphere.strips[1][3] = 1000;
  test::ScratchDir dir;
  const auto file = dir.write("bad_strip.ply", stripPly(sphere, PlyFormat::kAscii, true));
  EXPECT_THAT(importError(file),
              StartsWith(file.string() + ": the import lost geometry: 3 strip triangles dropped "
                                         "(vertex index out of range)"));
  const ImportedMeshes accepted = importMeshFile(file, {.acceptLossy = true});
  EXPECT_EQ(accepted.meshes[0].triangles.size(), 2u * 6 * 3 - 3);
  EXPECT_THAT(accepted.warnings, ElementsAre(HasSubstr("3 strip triangles dropped")));
}

TEST(PlyStrips, StripsOfNonIntegerIndicesAreRefusedByName) {
  test::ScratchDir dir;
  const auto file =
      dir.write("float_strips.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nelement tristrips 1\nproperty list int float vertex_indices\n"
                "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(importError(file, {.acceptLossy = true}),
            file.string() +
                ": PLY element 'tristrips': list 'vertex_indices' holds non-integer "
                "vertex indices: cannot read its triangle strips");
}

TEST(PlyStrips, VerticesWithoutPositionsAreRefusedByName) {
  test::ScratchDir dir;
  const auto file = dir.write("no_xyz.ply",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float a\n"
                              "element tristrips 1\nproperty list int int vertex_indices\n"
                              "end_header\n0\n1\n2\n3 0 1 2\n");
  EXPECT_EQ(importError(file), file.string() +
                                   ": PLY element 'vertex' has no x, y and z "
                                   "properties: no positions");
}

}  // namespace
}  // namespace softbake
