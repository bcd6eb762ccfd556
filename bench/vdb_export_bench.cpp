/// Times VdbSequenceWriter::write for one frame of a unit icosphere of 81,920 faces (subdivision
/// 6, 40,962 particles) at a voxel size of 1/200 of its diameter (0.01), the issue 5 target. Each
/// iteration builds the level set, the closest-triangle index, the `vel` grid (when asked) and
/// writes the compressed file to a temporary directory, so the figure is a whole frame.
/// Arguments are {TBB threads, velocity, compression: 0 zip, 1 Blosc, 2 none}.
///
///   cmake --build build-bench --target vdb_export_bench && build-bench/bench/vdb_export_bench

#include <benchmark/benchmark.h>
#include <stdlib.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "core/icosphere.hpp"
#include "core/world.hpp"
#include "exporters/vdb_sequence_writer.hpp"

namespace softbake {
namespace {

World ballWorld() {
  SceneSetup setup;
  setup.name = "bench";
  BodySetup body;
  body.name = "ball";
  body.mesh = makeIcosphere(6, 1.0f);
  setup.bodies.push_back(std::move(body));
  return buildWorld(setup);
}

void VdbExportFrame(benchmark::State& state) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    std::size_t(state.range(0)));
  static const World world = ballWorld();
  std::string directory =
      (std::filesystem::temp_directory_path() / "softbake-vdb-bench-XXXXXX").string();
  if (!::mkdtemp(directory.data())) throw std::runtime_error("mkdtemp failed");

  VdbOptions options;
  options.voxelSize = 2.0 / 200;
  options.velocity = state.range(1) != 0;
  options.compression = state.range(2) == 0   ? VdbOptions::Compression::Zip
                        : state.range(2) == 1 ? VdbOptions::Compression::Blosc
                                              : VdbOptions::Compression::None;
  VdbSequenceWriter writer(world, directory, "bench", options);
  Frame frame;
  frame.positions = world.position;
  frame.velocities.assign(world.particleCount(), Vec3(0, -1, 0));
  for (auto _ : state) {
    writer.write(frame);
    ++frame.number;
  }
  state.counters["faces"] = double(world.triangles.size());
  state.counters["MiB/frame"] =
      double(writer.bytesWritten()) / double(state.iterations()) / double(1 << 20);
  std::filesystem::remove_all(directory);
}
BENCHMARK(VdbExportFrame)
    ->ArgNames({"threads", "vel", "compression"})
    ->ArgsProduct({{1, 2}, {0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace softbake

BENCHMARK_MAIN();
