// The rows a PLY file really holds. assimp 5.2 pads an ascii file's missing rows with copies of
// the last one it read, so a file cut short looks whole to it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/mesh_import.hpp"
#include "importers/ply_data.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr float kCube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
constexpr int kCubeFaces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7},
                                   {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},
                                   {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string cubeHeader(std::string_view format) {
  return cat("ply\nformat ", format,
             " 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 12\nproperty list uchar int vertex_indices\nend_header\n");
}

// The cube with only its first `faces` faces written.
std::string asciiCube(int faces) {
  std::string text = cubeHeader("ascii");
  for (const auto& p : kCube) text += cat(p[0], " ", p[1], " ", p[2], "\n");
  for (int f = 0; f < faces; ++f)
    text += cat("3 ", kCubeFaces[f][0], " ", kCubeFaces[f][1], " ", kCubeFaces[f][2], "\n");
  return text;
}

std::string binaryCube(int faces) {
  std::string text = cubeHeader("binary_little_endian");
  for (const auto& p : kCube) text.append(reinterpret_cast<const char*>(p), sizeof p);
  for (int f = 0; f < faces; ++f) {
    text += char(3);
    text.append(reinterpret_cast<const char*>(kCubeFaces[f]), sizeof kCubeFaces[f]);
  }
  return text;
}

std::vector<std::uint64_t> rowsOf(const std::string& file) {
  const PlyHeader header = parsePlyHeader(file, file.size(), "t.ply");
  return countPlyRows(header, std::string_view(file).substr(header.dataOffset), "t.ply");
}

using test::importError;

TEST(PlyData, CountsTheWholeRowsOfEachElement) {
  static_assert(std::endian::native == std::endian::little, "binaryCube writes native order");
  EXPECT_THAT(rowsOf(asciiCube(12)), ElementsAre(8, 12));
  EXPECT_THAT(rowsOf(asciiCube(5)), ElementsAre(8, 5));
  EXPECT_THAT(rowsOf(binaryCube(12)), ElementsAre(8, 12));
  EXPECT_THAT(rowsOf(binaryCube(7)), ElementsAre(8, 7));
  // A row cut within its list is not counted.
  std::string cut = asciiCube(3) + "3 1 2";
  EXPECT_THAT(rowsOf(cut), ElementsAre(8, 3));
  cut = binaryCube(3) + std::string("\3\1\0\0\0", 5);
  EXPECT_THAT(rowsOf(cut), ElementsAre(8, 3));
}

TEST(PlyData, NamesTheRowAndPropertyOfAValueThatIsNotANumber) {
  std::string text = asciiCube(12);
  text.replace(text.find("\n1 0 0\n") + 3, 1, "abc");  // vertex 2's y
  try {
    rowsOf(text);
    FAIL() << "accepted";
  } catch (const Error& error) {
    EXPECT_EQ(std::string(error.what()),
              "t.ply: PLY data: element 'vertex' row 2 property 'y': 'abc' is not a number");
  }
}

TEST(PlyData, AnAsciiFileCutShortIsALossNamingTheFileAndTheCounts) {
  test::ScratchDir dir;
  const auto file = dir.write("half_cube.ply", asciiCube(6));
  EXPECT_THAT(importError(file),
              StartsWith(file.string() + ": the import lost geometry: the header declares 12 "
                                         "faces, the file holds 6"));
  const ImportedMeshes accepted = importMeshFile(file, {.acceptLossy = true});
  ASSERT_EQ(accepted.meshes.size(), 1u);
  EXPECT_THAT(accepted.warnings, ElementsAre(HasSubstr("the header declares 12 faces")));
  // The whole cube is no loss.
  const auto whole = dir.write("cube.ply", asciiCube(12));
  EXPECT_EQ(importMeshFile(whole).meshes[0].triangles.size(), 12u);
}

TEST(PlyData, ABinaryFileCutShortInItsListsIsRefusedEvenWhenLossIsAccepted) {
  test::ScratchDir dir;
  // Long enough for the header check's lower bound (a byte per face), too short for the faces.
  const auto file = dir.write("half_cube.ply", binaryCube(6));
  EXPECT_EQ(importError(file, {.acceptLossy = true}),
            file.string() +
                ": PLY data: the header declares 12 faces, the file holds 6 (truncated file)");
  const auto whole = dir.write("cube.ply", binaryCube(12));
  EXPECT_EQ(importMeshFile(whole).meshes[0].triangles.size(), 12u);
}

}  // namespace
}  // namespace softbake
