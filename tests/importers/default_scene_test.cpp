// The built-in default scene and its copy in examples/.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/mesh/mesh_topology.hpp"
#include "core/mesh/weld.hpp"
#include "importers/scene_file.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

TEST(DefaultScene, ExamplesCopyMatchesTheBuiltInText) {
  const std::filesystem::path example = test::sourceDir() / "examples" / "default.json";
  std::ifstream in(example);
  ASSERT_TRUE(in) << example;
  std::ostringstream text;
  text << in.rdbuf();
  EXPECT_EQ(nlohmann::json::parse(text.str()), nlohmann::json::parse(defaultSceneJson()));
  // And the copy loads as a scene file in its own right.
  EXPECT_EQ(loadSceneFile(example).setup.bodies.size(), 2u);
}

TEST(DefaultScene, TwoRubberBallsThrownAtEachOtherOverTheGround) {
  const SceneFile scene = defaultScene();
  EXPECT_EQ(scene.setup.name, "default");
  EXPECT_EQ(scene.setup.settings.fps, 24);
  EXPECT_EQ(scene.setup.settings.frames, 240);
  EXPECT_EQ(scene.setup.settings.substeps, 0);
  EXPECT_TRUE(scene.notes.empty());

  struct Ball {
    const char* name;
    Vec3f center;
    Vec3 velocity;
  };
  const Ball balls[] = {{"ballA", {-1.2f, 1.5f, 0}, {2.5f, 2, 0}},
                        {"ballB", {1.2f, 1.8f, 0}, {-2.5f, 1.5f, 0}}};
  ASSERT_EQ(scene.setup.bodies.size(), 2u);
  const Material rubber = *findMaterialPreset("rubber");
  for (std::size_t i = 0; i < 2; ++i) {
    const BodySetup& body = scene.setup.bodies[i];
    EXPECT_EQ(body.name, balls[i].name);
    EXPECT_EQ(body.velocity, balls[i].velocity);
    EXPECT_EQ(body.material.stiffness, rubber.stiffness);
    EXPECT_EQ(body.material.pressure, rubber.pressure);
    EXPECT_EQ(body.mesh.positions.size(), 642u);  // subdivision level 3
    EXPECT_EQ(body.mesh.triangles.size(), 1280u);
    for (const Vec3f& p : body.mesh.positions)
      EXPECT_NEAR((p - balls[i].center).norm(), 0.5f, 1e-5f);
    const WeldedMesh welded = weldByPosition(body.mesh.positions, body.mesh.triangles);
    EXPECT_TRUE(buildTopology(welded.triangles).closed());
    EXPECT_GT(signedVolume(welded.positions, welded.triangles), 0);
  }
  ASSERT_EQ(scene.setup.planes.size(), 1u);
  EXPECT_EQ(scene.setup.planes[0].name, "ground");
  EXPECT_EQ(scene.setup.planes[0].point, Vec3::Zero());
  EXPECT_EQ(scene.setup.planes[0].normal, Vec3::UnitY());
}

TEST(DefaultScene, EveryExampleSceneLoads) {
  std::size_t scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::sourceDir() / "examples")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW({
      const SceneFile scene = loadSceneFile(entry.path());
      EXPECT_FALSE(scene.setup.bodies.empty());
    });
    ++scenes;
  }
  EXPECT_GE(scenes, 1u);
}

}  // namespace
}  // namespace softbake
