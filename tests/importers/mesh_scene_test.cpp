// sceneFromMeshFile: a mesh file dropped on the ground, rescaled to about a metre when needed.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "generated_meshes.hpp"
#include "importers/scene_file.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

Eigen::AlignedBox3f boundsOf(const SceneSetup& setup) {
  Eigen::AlignedBox3f bounds;
  for (const BodySetup& body : setup.bodies)
    for (const Triangle& t : body.mesh.triangles)
      for (Index v : t) bounds.extend(body.mesh.positions[v]);
  return bounds;
}

void expectDroppedOnTheGround(const SceneFile& scene, const std::string& name) {
  EXPECT_EQ(scene.setup.name, name);
  EXPECT_EQ(scene.setup.settings.fps, 24);
  EXPECT_EQ(scene.setup.settings.frames, 240);
  EXPECT_EQ(scene.setup.settings.substeps, 0);
  ASSERT_EQ(scene.setup.planes.size(), 1u);
  EXPECT_EQ(scene.setup.planes[0].name, "ground");
  EXPECT_EQ(scene.setup.planes[0].normal, Vec3::UnitY());
  const Eigen::AlignedBox3f bounds = boundsOf(scene.setup);
  EXPECT_NEAR(bounds.min().y(), 0.5f, 1e-5f);
  EXPECT_NEAR(bounds.center().x(), 0, 1e-5f);
  EXPECT_NEAR(bounds.center().z(), 0, 1e-5f);
  for (const BodySetup& body : scene.setup.bodies) {
    EXPECT_EQ(body.material.stiffness, findMaterialPreset("rubber")->stiffness);
    EXPECT_EQ(body.mesh.name, body.name);
  }
}

TEST(MeshScene, ScalesTheSmallScanUpToAMetre) {
  test::ScratchDir dir;
  const auto file = dir.write("scan.ply", test::ScanPly::text());
  const SceneFile scene = sceneFromMeshFile(file);
  expectDroppedOnTheGround(scene, "scan");
  ASSERT_EQ(scene.setup.bodies.size(), 1u);
  EXPECT_EQ(scene.setup.bodies[0].name, "scan");
  EXPECT_NEAR(boundsOf(scene.setup).sizes().maxCoeff(), 1, 1e-5);
  ASSERT_EQ(scene.notes.size(), 1u);
  EXPECT_EQ(scene.notes[0],
            file.string() + ": scaled by 6.25 to about a metre (its largest side was 0.16 units)");
}

TEST(MeshScene, ScalesTheLargeBallDownToAMetre) {
  const auto file = test::testMeshes() / "ballA.off";
  const SceneFile scene = sceneFromMeshFile(file);
  expectDroppedOnTheGround(scene, "ballA");
  EXPECT_NEAR(boundsOf(scene.setup).sizes().maxCoeff(), 1, 1e-5);
  ASSERT_EQ(scene.notes.size(), 1u);
  EXPECT_EQ(
      scene.notes[0],
      file.string() + ": scaled by 0.0722 to about a metre (its largest side was 13.9 units)");
}

TEST(MeshScene, LeavesMetreSizedMeshesAlone) {
  test::ScratchDir dir;
  const SceneFile scene = sceneFromMeshFile(dir.write("textured.obj", test::TexturedObj::text()));
  expectDroppedOnTheGround(scene, "textured");
  EXPECT_TRUE(scene.notes.empty());
  EXPECT_NEAR(boundsOf(scene.setup).sizes().maxCoeff(), test::TexturedObj::kLargestSide, 1e-6);
}

TEST(MeshScene, OneBodyPerMeshOfAMultiMeshFile) {
  const SceneFile scene =
      sceneFromMeshFile(test::testMeshes() / "cubes_with_mirroring_and_pivot.fbx");
  const std::string stem = "cubes_with_mirroring_and_pivot";
  expectDroppedOnTheGround(scene, stem);
  std::vector<std::string> names;
  for (const BodySetup& body : scene.setup.bodies) names.push_back(body.name);
  EXPECT_EQ(names, (std::vector<std::string>{stem + "/Cube2", stem + "/Cube1", stem + "/Cube3",
                                             stem + "/Cube1_2"}));
  EXPECT_TRUE(scene.notes.empty());  // 0.33 across: within [0.25, 4]
}

}  // namespace
}  // namespace softbake
