// The implicit integrator's own solver (core/dynamics/implicit_euler). What it shares with XPBD
// (stability, conservation, free fall, resting volume, determinism) is in
// stable_integrators_test; pins in forces_test.
#include "core/dynamics/implicit_euler.hpp"

#include <gtest/gtest.h>

#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

SceneSetup implicitBall(const char* preset, bool gravity = true, bool ground = true) {
  SceneSetup scene =
      test::ballScene(*findMaterialPreset(preset), 3, 0.5f, {0, 1, 0}, gravity, ground);
  scene.settings.integrator = IntegratorKind::Implicit;
  return scene;
}

TEST(ImplicitEuler, TheSolverConvergesToItsTolerance) {
  SceneSetup scene = implicitBall("stiff", /*gravity=*/true, /*ground=*/true);
  scene.settings.substeps = 1;
  Simulator simulator(buildSceneTopology(scene));
  for (int frame = 2; frame <= 12; ++frame) {
    simulator.advanceToFrame(frame);
    const std::optional<ImplicitSolveStats> solve = simulator.lastSolve();
    ASSERT_TRUE(solve);
    EXPECT_LT(solve->iterations, ImplicitEuler::kMaxIterations) << "frame " << frame;
    EXPECT_LE(solve->relativeResidual, ImplicitEuler::kTolerance) << "frame " << frame;
  }
}

}  // namespace
}  // namespace softbake
