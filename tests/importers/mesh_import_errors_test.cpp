// What importMeshFile says about files it cannot use. Every message starts with the file's path.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "importers/memory_budget.hpp"
#include "importers/mesh_import.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

using test::importError;

TEST(MeshImportErrors, MissingFile) {
  test::ScratchDir dir;
  const auto file = dir / "nothing_here.obj";
  EXPECT_EQ(importError(file), file.string() + ": file not found");
}

TEST(MeshImportErrors, Directory) {
  test::ScratchDir dir;
  EXPECT_EQ(importError(dir.path()), dir.path().string() + ": is a directory, not a mesh file");
}

TEST(MeshImportErrors, UnsupportedFormatIncludesAssimpsReason) {
  test::ScratchDir dir;
  const auto file = dir.write("notes.xyzzy", "these are not the vertices you are looking for\n");
  const std::string message = importError(file);
  EXPECT_THAT(message, StartsWith(file.string() + ": unsupported format (assimp: "));
  EXPECT_THAT(message, HasSubstr("No suitable reader found"));
}

TEST(MeshImportErrors, EmptyObjFromTheSharedBrokenFiles) {
  const auto file = test::testMeshes() / "broken" / "empty.obj";
  EXPECT_EQ(importError(file), file.string() + ": cannot import (assimp: OBJ-file is too small.)");
}

TEST(MeshImportErrors, OnlyPointsAndLines) {
  test::ScratchDir dir;
  const auto file = dir.write("wire.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\np 1\n");
  EXPECT_EQ(importError(file),
            file.string() + ": no triangles (the file holds only points and lines)");
}

TEST(MeshImportErrors, NonFiniteCoordinates) {
  test::ScratchDir dir;
  // 1e39 overflows float: assimp hands over infinity.
  const auto file = dir.write("huge.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THAT(importError(file),
              StartsWith(file.string() +
                         ": mesh 'defaultobject': vertex 1 has non-finite coordinates (inf"));
}

// UVs are written again in every OBJ frame: a NaN there would reach the output. (assimp's OBJ
// reader turns an overflowing `vt` into 0, so the NaN comes in a binary PLY.)
TEST(MeshImportErrors, NonFiniteTextureCoordinates) {
  test::ScratchDir dir;
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty float u\nproperty float v\n"
      "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float vertices[3][5] = {{0, 0, 0, 0, 0}, {1, 0, 0, nan, 0}, {0, 1, 0, 0, 1}};
  ply.append(reinterpret_cast<const char*>(vertices), sizeof vertices);
  const std::uint32_t face[3] = {0, 1, 2};
  ply += char(3);
  ply.append(reinterpret_cast<const char*>(face), sizeof face);
  const auto file = dir.write("nan_uv.ply", ply);
  EXPECT_EQ(
      importError(file),
      file.string() + ": mesh 'nan_uv': vertex 1 has non-finite texture coordinates (nan, 0)");
}

TEST(MeshImportErrors, PlyHeadersAreCheckedBeforeAssimpSeesThem) {
  test::ScratchDir dir;
  const auto file = dir.write("bad.ply",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                              "property flaot y\nend_header\n0 0\n1 0\n0 1\n");
  EXPECT_EQ(importError(file), file.string() + ": PLY header line 5: unknown type 'flaot'");
  // Content decides, not the extension: the same bytes under another name are checked too.
  const auto renamed =
      dir.write("bad.mesh", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n");
  EXPECT_EQ(
      importError(renamed),
      renamed.string() + ": PLY header line 3: element 'vertex' has 3 rows but no properties");
  // And a .ply that is not PLY at all never reaches assimp's PLY reader.
  const auto impostor = dir.write("impostor.ply", "solid x\nendsolid x\n");
  EXPECT_EQ(importError(impostor),
            impostor.string() + ": PLY header line 1: expected 'ply' (not a PLY file)");
}

TEST(MeshImportErrors, PlyDeclaringMoreRowsThanMemoryCanHold) {
  test::ScratchDir dir;
  // ASCII rows have no fixed size, so only the memory estimate stops this one once the vertex
  // cap (import_limits_test.cpp) is out of the way.
  const auto file = dir.write("liar.ply",
                              "ply\nformat ascii 1.0\nelement vertex 1000000000000000\n"
                              "property float x\nproperty float y\nproperty float z\nend_header\n"
                              "0 0 0\n");
  const std::string message =
      importError(file, {.limits = {.maxVertices = std::numeric_limits<std::uint64_t>::max()}});
  EXPECT_THAT(message,
              StartsWith(file.string() +
                         ": mesh too large for this machine: reading the PLY file needs about "));
  EXPECT_THAT(message, HasSubstr(" of memory"));
}

TEST(MemoryBudget, RefusesWhatDoesNotFit) {
  EXPECT_NO_THROW(requireMemory("a.obj", 1000, "importing 1 mesh instances", 1000));
  EXPECT_NO_THROW(requireMemory("a.obj", 1e30, "anything", 0));  // unknown budget
  try {
    requireMemory("a.obj", 3.5 * 1024 * 1024 * 1024, "importing 2 mesh instances",
                  1024 * 1024 * 1024);
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_STREQ(error.what(),
                 "a.obj: mesh too large for this machine: importing 2 mesh instances needs about "
                 "3.5 GiB, but it has 1.0 GiB of memory");
  }
  EXPECT_GT(physicalMemoryBytes(), 64u * 1024 * 1024);
  EXPECT_EQ(formatBytes(512), "512 bytes");
  EXPECT_EQ(formatBytes(1536), "1.5 KiB");
}

}  // namespace
}  // namespace softbake
