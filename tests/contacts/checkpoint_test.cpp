// A run continued from a checkpoint comes out bit for bit as the run that was not stopped, on
// another thread count too: the ground the simulation cache's --resume stands on. Examples that
// exercise every piece of state a frame carries over: the implicit warm start and plane holds, the
// broad phase's touching pairs
// ("auto" substeps), pins, self-collision, and bodies that start inside each other.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <tuple>

#include "core/error.hpp"
#include "core/simulator.hpp"
#include "importers/scene_file.hpp"

namespace softbake {
namespace {

bool sameBytes(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

class Checkpoint : public ::testing::TestWithParam<std::tuple<std::string, IntegratorKind>> {};

TEST_P(Checkpoint, ARestoredRunContinuesBitForBit) {
  const auto& [example, integrator] = GetParam();
  SceneFile file =
      loadSceneFile(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "examples" / (example + ".json"));
  file.setup.settings.integrator = integrator;
  // A count an example pins is for its own integrator; the explicit one needs its stability bound.
  if (integrator == IntegratorKind::Explicit) file.setup.settings.substeps = 0;
  const auto topology = std::make_shared<const SceneTopology>(buildSceneTopology(file.setup));
  // Frames 2–4 ahead of the checkpoint (glued_assembly is still tangled there), 5–10 after it.
  constexpr int kCheckpointFrame = 4, kLastFrame = 10;
  // The run on three threads, resumed on one: a bake resumed on another machine, or with
  // another -j, comes out the same.
  Simulator original(topology);
  SimulationCheckpoint checkpoint;
  tbb::task_arena(3).execute([&] {
    for (int frame = 2; frame <= kCheckpointFrame; ++frame) original.advanceToFrame(frame);
    checkpoint = original.checkpoint();
    for (int frame = kCheckpointFrame + 1; frame <= kLastFrame; ++frame)
      original.advanceToFrame(frame);
  });

  Simulator resumed(topology);
  resumed.restore(checkpoint);
  tbb::task_arena(1).execute([&] {
    for (int frame = kCheckpointFrame + 1; frame <= kLastFrame; ++frame)
      resumed.advanceToFrame(frame);
  });
  EXPECT_TRUE(sameBytes(resumed.state().position, original.state().position)) << "positions";
  EXPECT_TRUE(sameBytes(resumed.state().velocity, original.state().velocity)) << "velocities";
  EXPECT_EQ(resumed.stepsTaken(), original.stepsTaken());
  EXPECT_GT(original.stepsTaken(), std::uint64_t(kLastFrame - 1)) << "several substeps a frame";
}

std::string checkpointTestName(const testing::TestParamInfo<Checkpoint::ParamType>& param) {
  return std::get<0>(param.param) + "_" + std::string(integratorName(std::get<1>(param.param)));
}

INSTANTIATE_TEST_SUITE_P(
    Examples, Checkpoint,
    ::testing::Combine(::testing::Values("default", "glued_assembly", "sheet_ball", "flag_fold",
                                         "heavy_on_jelly"),
                       ::testing::Values(IntegratorKind::Explicit, IntegratorKind::Implicit,
                                         IntegratorKind::Xpbd)),
    checkpointTestName);

TEST(CheckpointRestore, ACheckpointOfAnotherSceneIsRefused) {
  SceneFile file =
      loadSceneFile(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "examples/fig4_two_bodies.json");
  Simulator simulator(buildSceneTopology(file.setup));
  SimulationCheckpoint checkpoint = simulator.checkpoint();
  checkpoint.state.position.pop_back();
  checkpoint.state.velocity.pop_back();
  EXPECT_THROW(simulator.restore(checkpoint), Error);
}

}  // namespace
}  // namespace softbake
