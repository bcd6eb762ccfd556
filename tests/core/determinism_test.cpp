// Results must be bit-identical for any thread count: every parallel loop writes its own element
// and every sum runs in a fixed order.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

std::vector<Vec3> simulate(int threads) {
  // An arena of exactly `threads`: more than this machine's cores too, as a studio's 16- to
  // 64-core machines run it; the global limit alone only lowers the default arena's.
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  tbb::task_arena arena(threads);
  return arena.execute([&] {
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
  });
}

TEST(Determinism, AnyThreadCountGivesBitIdenticalPositions) {
  const std::vector<Vec3> one = simulate(1);
  for (int threads : {2, 3, 4}) {
    const std::vector<Vec3> many = simulate(threads);
    ASSERT_EQ(one.size(), many.size());
    for (std::size_t i = 0; i < one.size(); ++i)
      ASSERT_EQ(one[i], many[i]) << "particle " << i << " at " << threads << " threads";
  }
}

}  // namespace
}  // namespace softbake
