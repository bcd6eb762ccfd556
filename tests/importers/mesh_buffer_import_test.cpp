// importMeshBuffer: a file already in memory (what the fuzz targets feed) imports as the same
// file on disk does, reads nothing but its bytes, and fails as clearly.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cctype>
#include <fstream>
#include <iterator>
#include <string>

#include "core/error.hpp"
#include "importers/mesh_import.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string bytesOf(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  EXPECT_TRUE(in) << "cannot read " << file;
  return {std::istreambuf_iterator<char>(in), {}};
}

std::string bufferError(std::string_view bytes, const std::string& name) {
  try {
    importMeshBuffer(bytes, name);
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "no error for " << name;
  return {};
}

class MeshBufferImport : public ::testing::TestWithParam<std::filesystem::path> {};

// Every format the fuzz target feeds, in both binary and text forms where there are two.
TEST_P(MeshBufferImport, GivesTheMeshesOfTheFileOnDisk) {
  const std::filesystem::path file = GetParam();
  const ImportedMeshes fromDisk = importMeshFile(file);
  const ImportedMeshes fromMemory =
      importMeshBuffer(bytesOf(file), file.filename().string(), MeshImportOptions{});
  ASSERT_EQ(fromMemory.meshes.size(), fromDisk.meshes.size());
  ASSERT_FALSE(fromMemory.meshes.empty());
  for (std::size_t m = 0; m < fromDisk.meshes.size(); ++m) {
    const TriangleMesh& expected = fromDisk.meshes[m];
    const TriangleMesh& got = fromMemory.meshes[m];
    EXPECT_EQ(got.name, expected.name);
    EXPECT_EQ(got.triangles, expected.triangles);
    EXPECT_EQ(got.positions, expected.positions);
    EXPECT_EQ(got.uvs, expected.uvs);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Formats, MeshBufferImport,
    ::testing::Values(test::testMeshes() / "ico4.obj", test::testMeshes() / "fuze.ply",
                      test::testMeshes() / "torus.STL", test::testMeshes() / "sphereWithHole.stl",
                      test::testMeshes() / "cubes_with_mirroring_and_pivot.fbx",
                      test::sourceDir() / "tests" / "data" / "import" / "box.gltf",
                      test::sourceDir() / "tests" / "data" / "import" / "box.glb"),
    [](const auto& test) {
      std::string name = test.param.filename().string();
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

TEST(MeshBufferImport, TheGlbIsTheClosedUnitCube) {
  const std::filesystem::path glb = test::sourceDir() / "tests" / "data" / "import" / "box.glb";
  const ImportedMeshes imported = importMeshBuffer(bytesOf(glb), "box.glb");
  ASSERT_EQ(imported.meshes.size(), 1u);
  EXPECT_EQ(imported.meshes[0].triangles.size(), 12u);
  EXPECT_EQ(imported.meshes[0].positions.size(), 8u);
}

// A buffer is all there is: the glTF's .bin beside it on disk is not read.
TEST(MeshBufferImport, CompanionFilesAreNotRead) {
  const std::filesystem::path gltf = test::testMeshes() / "AnimatedMorphSphere.gltf";
  ASSERT_NO_THROW(importMeshFile(gltf));
  EXPECT_THAT(bufferError(bytesOf(gltf), gltf.string()), StartsWith(gltf.string() + ": "));
}

TEST(MeshBufferImport, EmptyAndUnknownBuffersAreRefusedByName) {
  EXPECT_EQ(bufferError("", "nothing.obj"), "nothing.obj: the file is empty");
  EXPECT_THAT(bufferError("not a mesh at all", "noise.xyzzy"),
              AllOf(StartsWith("noise.xyzzy: "), HasSubstr("assimp")));
}

// The PLY guard runs on buffers too, by content as well as by name: this truncated header makes
// assimp 5.2 segfault.
TEST(MeshBufferImport, ThePlyGuardProtectsBuffersToo) {
  const std::string crash =
      bytesOf(test::testMeshes() / "broken" / "crash-30d6d0f7c529b3b66b4131700b7a4580cd7082df.ply");
  EXPECT_THAT(bufferError(crash, "crash.ply"), StartsWith("crash.ply: PLY header line "));
  EXPECT_THAT(bufferError(crash, "crash.bin"), StartsWith("crash.bin: PLY header line "));
}

}  // namespace
}  // namespace softbake
