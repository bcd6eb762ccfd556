// The broad phases on real meshes from tests/data/meshes, overlapping and deformed by a real
// simulation: every kind and every sbhash level finds exactly brute force's pairs.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "core/broad_phase/broad_phase.hpp"
#include "core/simulator.hpp"
#include "generated_meshes.hpp"
#include "importers/mesh_import.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

/// The file's meshes merged, scaled so the largest side is one metre and centred on `centre`.
TriangleMesh unitMesh(const std::filesystem::path& file, const Vec3f& centre) {
  TriangleMesh mesh = importMeshFile(file, {.mergeMeshes = true}).meshes.at(0);
  Eigen::AlignedBox3f bounds;
  for (const Vec3f& p : mesh.positions) bounds.extend(p);
  const float scale = 1.0f / bounds.sizes().maxCoeff();
  for (Vec3f& p : mesh.positions) p = (p - bounds.center()) * scale + centre;
  return mesh;
}

TEST(BroadPhaseOnRealMeshes, EveryKindAndLevelFindsBruteForcesPairsWhileTheyDeform) {
  SceneSetup scene;
  test::ScratchDir dir;
  const std::filesystem::path meshes = test::testMeshes();
  const struct {
    std::filesystem::path file;
    Vec3f centre;
  } bodies[] = {{dir.write("textured.obj", test::TexturedObj::text()), Vec3f(0, 1, 0)},
                {meshes / "duck.dae", Vec3f(0.45f, 1.2f, 0.1f)},
                {meshes / "fels.3ds", Vec3f(-0.4f, 1.1f, -0.2f)},
                {meshes / "ballA.off", Vec3f(0.1f, 1.6f, 0.3f)},
                {meshes / "sphereWithHole.stl", Vec3f(0.2f, 0.7f, -0.3f)}};  // open: self-collides
  for (const auto& body : bodies) {
    BodySetup setup;
    setup.name = body.file.filename().string();
    setup.mesh = unitMesh(body.file, body.centre);
    setup.material = *findMaterialPreset("jelly");
    scene.bodies.push_back(std::move(setup));
  }
  StaticMeshCollider torus;
  torus.name = "torus";
  torus.mesh = unitMesh(meshes / "torus.STL", Vec3f(0, 0.4f, 0));
  scene.staticMeshes.push_back(std::move(torus));
  scene.settings.collisions.response = ResponseMode::None;  // let them sink into each other
  Simulator simulator(buildSceneTopology(scene));

  std::unique_ptr<BroadPhase> brute = makeBroadPhase(BroadPhaseKind::BruteForce);
  std::vector<std::unique_ptr<BroadPhase>> others;
  for (int levels = 1; levels <= 4; ++levels)
    others.push_back(makeBroadPhase(BroadPhaseKind::Sbhash, {.subdivisionLevels = levels}));
  others.push_back(makeBroadPhase(BroadPhaseKind::SpatialHash));
  others.push_back(makeBroadPhase(BroadPhaseKind::Bvh));

  std::vector<TrianglePair> expected, found;
  std::vector<Box3> boxes;
  for (int round = 0; round < 3; ++round) {
    for (int s = 0; s < 40; ++s) simulator.step(2);  // deform between the checks
    const std::vector<Vec3>& now = simulator.state().position;
    updateCollisionBoxes(simulator.topology(), simulator.collision(), {now, now}, boxes);
    const BroadPhaseInput input = simulator.collision().broadPhaseInput(boxes);
    brute->findPairs(input, expected);
    ASSERT_GT(expected.size(), 1000u) << "the bodies must overlap for the test to mean anything";
    for (std::size_t k = 0; k < others.size(); ++k) {
      others[k]->findPairs(input, found);
      EXPECT_TRUE(found == expected)
          << broadPhaseName(others[k]->kind()) << " #" << k << " in round " << round << ": "
          << found.size() << " pairs, brute force " << expected.size();
    }
  }
}

}  // namespace
}  // namespace softbake
