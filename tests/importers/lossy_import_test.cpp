// Geometry lost on the way in: refused naming the file and what was lost, or imported with a
// warning when the loss is accepted; and assimp's log reaching the user, per file and per thread.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <assimp/DefaultLogger.hpp>

#include <nlohmann/json.hpp>
#include <thread>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/assimp_log.hpp"
#include "importers/import_losses.hpp"
#include "importers/mesh_import.hpp"
#include "importers/scene_file.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::Contains;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::StartsWith;

std::filesystem::path importData(std::string_view name) {
  return test::sourceDir() / "tests" / "data" / "import" / name;
}

using test::importError;

// A PLY of `vertices` points on a line, the first `faces` triangles of them used.
std::string plyWithUnusedVertices(int vertices, int faces) {
  std::string text = cat("ply\nformat ascii 1.0\nelement vertex ", vertices,
                         "\nproperty float x\nproperty float y\nproperty float z\nelement face ",
                         faces, "\nproperty list uchar int vertex_indices\nend_header\n");
  for (int v = 0; v < vertices; ++v) text += cat(v, " ", v % 2, " ", v % 3, "\n");
  for (int f = 0; f < faces; ++f) text += cat("3 ", 3 * f, " ", 3 * f + 1, " ", 3 * f + 2, "\n");
  return text;
}

TEST(LossyImport, TheIntactBoxLoadsWhole) {
  const ImportedMeshes imported = importMeshFile(importData("box.gltf"));
  ASSERT_EQ(imported.meshes.size(), 1u);
  EXPECT_EQ(imported.meshes[0].triangles.size(), 12u);
  EXPECT_THAT(imported.warnings, IsEmpty());
}

TEST(LossyImport, AFaceAssimpDropsForAnOutOfRangeIndexIsRefusedNamingTheFile) {
  const auto file = importData("box_out_of_range_index.gltf");
  const std::string message = importError(file);
  EXPECT_THAT(message, StartsWith(file.string() + ": the import lost geometry: faces dropped "
                                                  "(assimp: Some faces had out-of-range indices"));
  EXPECT_THAT(message, HasSubstr("--accept-lossy-import"));
}

TEST(LossyImport, AcceptedTheRestLoadsWithAWarningNamingTheFileAndTheLoss) {
  const auto file = importData("box_out_of_range_index.gltf");
  const ImportedMeshes imported = importMeshFile(file, {.acceptLossy = true});
  ASSERT_EQ(imported.meshes.size(), 1u);
  EXPECT_EQ(imported.meshes[0].triangles.size(), 11u);
  // What was lost in assimp's own words, once.
  EXPECT_THAT(imported.warnings,
              ElementsAre(file.string() +
                          ": the import lost geometry: faces dropped (assimp: Some faces had "
                          "out-of-range indices. Those faces were dropped.); imported what is "
                          "left (lossy import accepted)"));
}

TEST(LossyImport, MostVerticesUnusedIsRefusedWithTheCount) {
  test::ScratchDir dir;
  const auto file = dir.write("sparse.ply", plyWithUnusedVertices(40, 1));
  EXPECT_THAT(importError(file),
              StartsWith(file.string() +
                         ": the import lost geometry: 37 of 40 vertices (92.5%) are used by no "
                         "face"));
  EXPECT_EQ(importMeshFile(file, {.acceptLossy = true}).meshes[0].triangles.size(), 1u);
}

TEST(LossyImport, AFewStrayVerticesAreAWarningOnly) {
  test::ScratchDir dir;
  // 3 of 33 unused: under a tenth, as the stray points of a scan.
  const auto file = dir.write("strays.ply", plyWithUnusedVertices(33, 10));
  const ImportedMeshes imported = importMeshFile(file);
  EXPECT_EQ(imported.meshes[0].triangles.size(), 10u);
  EXPECT_THAT(imported.warnings,
              Contains(file.string() + ": assimp: Validation warning: There are unreferenced "
                                       "vertices"));
}

TEST(LossyImport, ASceneFileCanAcceptTheLossAndItsWarningsNameTheKey) {
  const std::string box = importData("box_out_of_range_index.gltf").string();
  const std::string bodies = cat(R"("bodies": [{"mesh": ")", box, R"("}])");
  const auto refused = [&] {
    try {
      parseScene(nlohmann::json::parse(cat("{", bodies, "}")), "scene.json", ".");
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  }();
  EXPECT_THAT(refused, StartsWith("scene.json: bodies[0].mesh: " + box +
                                  ": the import lost geometry: faces dropped"));

  const SceneFile scene =
      parseScene(nlohmann::json::parse(
                     cat(R"({"settings": {"import": {"accept_lossy": true}}, )", bodies, "}")),
                 "scene.json", ".");
  ASSERT_EQ(scene.setup.bodies.size(), 1u);
  EXPECT_EQ(scene.setup.bodies[0].mesh.triangles.size(), 11u);
  EXPECT_THAT(scene.warnings, Contains(StartsWith("scene.json: bodies[0].mesh: " + box +
                                                  ": the import lost geometry")));
  // The command line's acceptance reaches the scene's meshes too.
  EXPECT_EQ(parseScene(nlohmann::json::parse(cat("{", bodies, "}")), "scene.json", ".",
                       {.acceptLossyImport = true})
                .setup.bodies.size(),
            1u);
}

TEST(LossyImport, EachThreadHearsOnlyItsOwnFilesMessages) {
  const auto bad = importData("box_out_of_range_index.gltf");
  const auto good = importData("box.gltf");
  std::vector<std::string> badWarnings, goodWarnings;
  bool badOk = true, goodOk = true;
  std::thread badThread([&] {
    for (int i = 0; i < 50; ++i) {
      const ImportedMeshes imported = importMeshFile(bad, {.acceptLossy = true});
      badOk &= imported.warnings.size() == 1 && imported.meshes[0].triangles.size() == 11;
    }
  });
  std::thread goodThread([&] {
    for (int i = 0; i < 50; ++i) {
      const ImportedMeshes imported = importMeshFile(good);
      goodOk &= imported.warnings.empty() && imported.meshes[0].triangles.size() == 12;
    }
  });
  badThread.join();
  goodThread.join();
  EXPECT_TRUE(badOk);
  EXPECT_TRUE(goodOk);
}

TEST(AssimpLog, RepeatsAreToldOnceWithTheirCountAndTheListEndsWithHowManyMore) {
  std::vector<std::string> lines;
  {
    const AssimpLogCapture capture;
    for (int i = 0; i < 3; ++i) Assimp::DefaultLogger::get()->warn("same again");
    Assimp::DefaultLogger::get()->info("narration is not kept");
    for (int i = 0; i < 4; ++i) Assimp::DefaultLogger::get()->error(cat("error ", i).c_str());
    lines = describeAssimpMessages("f.obj", capture.messages(), capture.unkept(), 3);
  }
  EXPECT_THAT(lines,
              ElementsAre("f.obj: assimp: same again (3 times)", "f.obj: assimp error: error 0",
                          "f.obj: assimp error: error 1", "f.obj: assimp: 2 more messages"));
}

TEST(AssimpLog, AnInnerCaptureTakesTheMessagesWhileItIsOpen) {
  const AssimpLogCapture outer;
  {
    const AssimpLogCapture inner;
    Assimp::DefaultLogger::get()->warn("inner");
    EXPECT_EQ(inner.messages().size(), 1u);
  }
  Assimp::DefaultLogger::get()->warn("outer");
  ASSERT_EQ(outer.messages().size(), 1u);
  EXPECT_EQ(outer.messages()[0].text, "outer");
}

TEST(LossyImport, AssimpMessagesThatLoseGeometryAreRecognised) {
  EXPECT_EQ(geometryLostIn("Some faces had out-of-range indices. Those faces were dropped."),
            "faces dropped");
  EXPECT_EQ(geometryLostIn("OFF: The number of faces in the header is incorrect"), "faces missing");
  EXPECT_EQ(geometryLostIn("3DS: Vertex index overflow)"), "faces changed (out-of-range index)");
  // Messages that lose no geometry.
  EXPECT_EQ(geometryLostIn("FBX-DOM: unsupported, newer format version, supported are only FBX "
                           "2011, FBX 2012 and FBX 2013, trying to read it nevertheless"),
            std::nullopt);
  EXPECT_EQ(geometryLostIn("Validation warning: There are unreferenced vertices"), std::nullopt);
}

}  // namespace
}  // namespace softbake
