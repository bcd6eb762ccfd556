#include "core/collision/plane_contact.hpp"

#include <gtest/gtest.h>

#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

test::StagedScene singleParticleOverGround(Vec3 start, Vec3 end, Vec3 velocity) {
  test::StagedScene scene = test::springPair(0, 0, 1, 1);
  scene.state.position = {end, Vec3(0, 5, 0)};
  scene.substepStart = {start, Vec3(0, 5, 0)};
  scene.state.velocity = {velocity, Vec3::Zero()};
  scene.topology.planes.push_back(PlaneCollider{});
  scene.topology.settings.skin = Scalar(1e-3);
  return scene;
}

std::size_t resolve(test::StagedScene& scene) {
  return resolvePlaneContacts(scene.topology, scene.substepStart, scene.state);
}

TEST(PlaneContact, CrossingParticleGoesToTheIntersectionPointPlusSkin) {
  test::StagedScene scene =
      singleParticleOverGround(Vec3(0, 0.1f, 0), Vec3(0.4f, -0.1f, 0), Vec3(2, -2, 0));
  EXPECT_EQ(resolve(scene), 1u);
  const SimulationState& world = scene.state;
  EXPECT_NEAR(world.position[0].x(), 0.2, 1e-6);  // halfway along the segment
  EXPECT_NEAR(world.position[0].y(), 1e-3, 1e-7);
  // e = 0.2: normal speed 2 comes back as 0.4. Friction μ = 0.3 removes μ·(1+e)·2 = 0.72 of the
  // tangential speed 2.
  EXPECT_NEAR(world.velocity[0].y(), 0.4, 1e-6);
  EXPECT_NEAR(world.velocity[0].x(), 2 - 0.72, 1e-6);
  EXPECT_EQ(world.position[1], Vec3(0, 5, 0)) << "a particle far above is untouched";
}

TEST(PlaneContact, FrictionNeverReversesTheSlide) {
  test::StagedScene scene =
      singleParticleOverGround(Vec3(0, 0.1f, 0), Vec3(0.01f, -0.1f, 0), Vec3(0.1f, -5, 0));
  scene.topology.planes[0].friction = 1;
  resolve(scene);
  EXPECT_EQ(scene.state.velocity[0].x(), 0);
}

TEST(PlaneContact, BallDroppedOnTheGroundNeverEndsAStepBelowIt) {
  Simulator simulator(buildSceneTopology(test::ballScene(*findMaterialPreset("rubber"))));
  const Scalar skin = simulator.topology().settings.skin;
  for (int frame = 2; frame <= 72; ++frame) {
    for (int s = 0; s < simulator.substeps().substeps; ++s) {
      simulator.step(frame);
      for (const Vec3& p : simulator.state().position) ASSERT_GE(p.y(), skin * 0.999f) << frame;
    }
  }
  // Three seconds later it rests on the ground, roughly round.
  const Vec3d c = test::centroid(simulator.state());
  EXPECT_GT(c.y(), 0.35);
  EXPECT_LT(c.y(), 0.55);
}

}  // namespace
}  // namespace softbake
