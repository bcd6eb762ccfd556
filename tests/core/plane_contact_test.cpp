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

// The frame's plane contacts, checked against every particle's height: a particle is listed when
// it is within `listedBelow` of the plane and never when it is above `neverAbove`.
void expectPlaneContactsMatchHeights(const Simulator& simulator, Scalar listedBelow,
                                     Scalar neverAbove) {
  const SimulationState& state = simulator.state();
  std::vector<char> listed(state.particleCount(), 0);
  for (const Contact& c : simulator.contacts()) {
    ASSERT_EQ(c.kind, ContactKind::Plane);
    ASSERT_LT(c.particle, state.particleCount());
    EXPECT_EQ(listed[c.particle], 0) << "particle " << c.particle << " listed twice";
    listed[c.particle] = 1;
    const Vec3& x = state.position[c.particle];
    EXPECT_EQ(c.surfaceA, 0u);
    EXPECT_EQ(c.surfaceB, 0u);
    EXPECT_EQ(c.normal, Vec3(0, 1, 0));
    EXPECT_NEAR(c.position.y(), 0, 1e-6) << "on the plane";
    EXPECT_EQ(c.position.x(), x.x());
    EXPECT_EQ(c.position.z(), x.z());
    EXPECT_LT(x.y(), neverAbove);
  }
  for (std::size_t i = 0; i < state.particleCount(); ++i) {
    const bool low = state.position[i].y() < listedBelow;
    EXPECT_TRUE(!low || listed[i]) << "particle " << i << " is on the plane but not listed";
  }
}

TEST(PlaneContact, AFrameListsTheParticlesOnTheGroundAndNoneInFlight) {
  Simulator simulator(buildSceneTopology(test::ballScene(*findMaterialPreset("rubber"))));
  const Scalar skin = simulator.topology().settings.skin;
  simulator.advanceToFrame(2);
  EXPECT_TRUE(simulator.contacts().empty()) << "the ball starts half a metre up";
  std::size_t mostOnTheGround = 0;
  for (int frame = 3; frame <= 48; ++frame) {
    simulator.advanceToFrame(frame);
    expectPlaneContactsMatchHeights(simulator, skin, skin * 1.01f);
    mostOnTheGround = std::max(mostOnTheGround, simulator.contacts().size());
  }
  EXPECT_GT(mostOnTheGround, 3u) << "the ball came to rest on more than a few particles";
}

TEST(PlaneContact, DetectionOnlyListsTheParticlesBehindThePlane) {
  SceneSetup setup = test::ballScene(*findMaterialPreset("rubber"));
  setup.settings.collisions.response = ResponseMode::None;
  Simulator simulator(buildSceneTopology(setup));
  std::size_t mostBehind = 0;
  for (int frame = 2; frame <= 24; ++frame) {
    simulator.advanceToFrame(frame);
    expectPlaneContactsMatchHeights(simulator, 0, 0);
    mostBehind = std::max(mostBehind, simulator.contacts().size());
  }
  EXPECT_GT(mostBehind, 100u) << "the ball fell through the ground, seen by the detector";
}

}  // namespace
}  // namespace softbake
