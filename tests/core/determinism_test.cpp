// Results must be bit-identical for any thread count: every parallel loop writes its own element
// and every sum runs in a fixed order.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

std::vector<Vec3> simulate(int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  SceneSetup scene = test::ballScene(*findMaterialPreset("balloon"), 4);
  BodySetup second = scene.bodies[0];
  second.name = "second";
  second.mesh = makeIcosphere(4, 0.4f, Vec3f(1.5f, 2, 0));
  second.material = *findMaterialPreset("jelly");
  second.velocity = Vec3(-1, 0, 0.5f);
  scene.bodies.push_back(second);
  // The paper's explicit Euler here; the stable integrators have their own (stable_integrators).
  scene.settings.integrator = IntegratorKind::Explicit;
  Simulator simulator(buildSceneTopology(scene));
  for (int frame = 2; frame <= 30; ++frame) simulator.advanceToFrame(frame);
  return simulator.state().position;
}

TEST(Determinism, OneAndTwoThreadsGiveBitIdenticalPositions) {
  const std::vector<Vec3> one = simulate(1);
  const std::vector<Vec3> two = simulate(2);
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t i = 0; i < one.size(); ++i) ASSERT_EQ(one[i], two[i]) << "particle " << i;
}

}  // namespace
}  // namespace softbake
