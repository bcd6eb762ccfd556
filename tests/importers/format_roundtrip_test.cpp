// One model written by assimp in many formats must come back as the same soft body: the same
// particle count after welding, and the same enclosed volume.

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include "core/mesh/mesh_topology.hpp"
#include "core/mesh/weld.hpp"
#include "generated_meshes.hpp"
#include "importers/mesh_import.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

struct Format {
  const char* exporterId;  ///< assimp's name for the exporter
  const char* fileName;
};

// Not "fbx": assimp 5.2 cannot read its own binary FBX back ("FBX-Tokenize (offset 0x1ef) block
// offset is out of range"), a writer bug that says nothing about our importer.
constexpr Format kFormats[] = {
    {"obj", "model.obj"},       {"stl", "model_ascii.stl"},   {"stlb", "model_binary.stl"},
    {"ply", "model_ascii.ply"}, {"plyb", "model_binary.ply"}, {"gltf2", "model.gltf"},
    {"glb2", "model.glb"},      {"collada", "model.dae"},     {"3ds", "model.3ds"},
    {"x3d", "model.x3d"},       {"assbin", "model.assbin"},
};

struct Body {
  std::size_t particles;
  double volume;
};

Body weldAll(const std::filesystem::path& file) {
  const ImportedMeshes imported = importMeshFile(file, {.mergeMeshes = true});
  const TriangleMesh& mesh = imported.meshes.at(0);
  const WeldedMesh welded = weldByPosition(mesh.positions, mesh.triangles);
  return {welded.positions.size(), signedVolume(welded.positions, welded.triangles)};
}

class FormatRoundTrip : public ::testing::TestWithParam<const char*> {};

/// A file of tests/data/meshes, or the generated stand-in of that name written into `dir`.
std::filesystem::path sourceFile(const std::string& name, const test::ScratchDir& dir) {
  if (name == "textured.obj") return dir.write(name, test::TexturedObj::text());
  return test::testMeshes() / name;
}

TEST_P(FormatRoundTrip, EveryFormatWeldsToTheSameBody) {
  test::ScratchDir dir;
  const std::filesystem::path source = sourceFile(GetParam(), dir);
  const Body original = weldAll(source);
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(source.string(), aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr);

  Assimp::Exporter exporter;
  for (const Format& format : kFormats) {
    SCOPED_TRACE(format.exporterId);
    const std::filesystem::path file = dir / format.fileName;
    ASSERT_EQ(exporter.Export(scene, format.exporterId, file.string()), aiReturn_SUCCESS)
        << exporter.GetErrorString();
    const Body copy = weldAll(file);
    EXPECT_EQ(copy.particles, original.particles);
    EXPECT_NEAR(copy.volume, original.volume, 1e-4 * original.volume);
  }
}

INSTANTIATE_TEST_SUITE_P(
    SharedMeshes, FormatRoundTrip, ::testing::Values("ico4.obj", "textured.obj"),
    [](const auto& param) {
      return std::string(param.param).substr(0, std::string(param.param).find('.'));
    });

// ico4: the shared snapshot README's "uniq pos"; the stand-in: its positions by construction.
TEST(FormatRoundTrip, OriginalsHaveTheirKnownCounts) {
  test::ScratchDir dir;
  EXPECT_EQ(weldAll(sourceFile("ico4.obj", dir)).particles, 642u);
  EXPECT_EQ(weldAll(sourceFile("textured.obj", dir)).particles, test::TexturedObj::kPositions);
}

}  // namespace
}  // namespace softbake
