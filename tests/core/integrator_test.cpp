#include "core/dynamics/integrator.hpp"

#include <gtest/gtest.h>

#include "core/dynamics/forces.hpp"
#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

TEST(Integrator, OneStepIsThePapersTwoEquations) {
  test::StagedScene pair =
      test::springPair(/*stiffness=*/40, /*damping=*/0, /*mass=*/2, /*length=*/1.25f);
  pair.topology.settings.gravity = Vec3(0, -9.81f, 0);
  pair.state.velocity[0] = Vec3(0.5f, 1, 0);
  const Vec3 x0 = pair.state.position[0], v0 = pair.state.velocity[0];
  const double dt = 0.01;
  ASSERT_TRUE(test::springStep(pair, Scalar(dt)));
  // By hand: f = m·g + k·(L − L0)·x̂ = (10, −19.62, 0); v1 = v0 + f/m·dt; x1 = x0 + v1·dt.
  const Vec3d f(40 * 0.25, -9.81 * 2, 0);
  const Vec3d v1 = v0.cast<double>() + f / 2 * dt;
  const Vec3d x1 = x0.cast<double>() + v1 * dt;
  EXPECT_NEAR((pair.state.velocity[0].cast<double>() - v1).norm(), 0, 1e-6);
  EXPECT_NEAR((pair.state.position[0].cast<double>() - x1).norm(), 0, 1e-6);
  EXPECT_EQ(pair.substepStart[0], x0);
}

TEST(Integrator, FreeFallHasTheSchemesKnownError) {
  Material material;
  material.pressure = 0;
  SceneSetup scene = test::ballScene(material, 2, 0.5f, {0, 10, 0}, true, false);
  scene.bodies[0].velocity = Vec3(1, 2, 0);
  scene.settings.integrator = IntegratorKind::Explicit;
  Simulator simulator(buildSceneTopology(scene));
  const Vec3d start = test::centroid(simulator.state());
  const int frames = 24;
  for (int frame = 2; frame <= frames + 1; ++frame) simulator.advanceToFrame(frame);
  const double t = frames / 24.0, dt = simulator.substeps().timeStep, g = 9.81;
  const Vec3d exact = start + Vec3d(1, 2, 0) * t - Vec3d(0, g * t * t / 2, 0);
  // Symplectic Euler uses the end-of-step velocity: x_n = x0 + v0·t − g·t²/2 − g·t·dt/2 exactly.
  const Vec3d scheme = exact - Vec3d(0, g * t * dt / 2, 0);
  const Vec3d got = test::centroid(simulator.state());
  EXPECT_NEAR((got - scheme).norm(), 0, 1e-4) << got.transpose() << " vs " << scheme.transpose();
  EXPECT_GT((got - exact).norm(), 0.5 * g * t * dt / 2);  // the error is really there
}

TEST(Integrator, NonFiniteVelocityIsReported) {
  test::StagedScene pair = test::springPair(40, 0, 1, 1);
  pair.state.velocity[1] = Vec3(std::numeric_limits<Scalar>::quiet_NaN(), 0, 0);
  EXPECT_FALSE(test::springStep(pair, Scalar(0.01)));
  EXPECT_EQ(findRunawayParticle(pair.topology, pair.state),
            0u);  // the spring carried the NaN to particle 0 too
}

TEST(Integrator, AbsurdSpeedIsReported) {
  test::StagedScene pair = test::springPair(40, 0, 1, 1);
  pair.topology.settings.maxSpeed = 100;
  pair.state.velocity[1] = Vec3(0, 150, 0);
  EXPECT_FALSE(test::springStep(pair, Scalar(0.001)));
  EXPECT_EQ(findRunawayParticle(pair.topology, pair.state), 1u);
}

}  // namespace
}  // namespace softbake
