/// Times VdbSequenceWriter::write for one frame of a unit sphere of ~10k or ~100k faces (cube
/// spheres of 10,092 and 99,372 faces) at a voxel size of 1/200 of its diameter (0.01), the issue
/// 5 target. Each iteration builds the level set, the `vel` grid (when asked) and writes the
/// compressed file to a temporary directory, so the figure is a whole frame.
/// Arguments are {faces, TBB threads, velocity, compression: 0 zip, 1 Blosc, 2 none}.
///
///   cmake --build build-bench --target vdb_export_bench && build-bench/bench/vdb_export_bench

#include <benchmark/benchmark.h>
#include <stdlib.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>

#include "core/mesh/cube_sphere.hpp"
#include "core/scene/scene_topology.hpp"
#include "exporters/vdb_sequence_writer.hpp"

namespace softbake {
namespace {

SceneTopology ballTopology(std::size_t faces) {
  SceneSetup setup;
  setup.name = "bench";
  BodySetup body;
  body.name = "ball";
  body.mesh = makeCubeSphere(cubeSphereDivisions(faces), 1.0f);
  setup.bodies.push_back(std::move(body));
  return buildSceneTopology(setup);
}

void VdbExportFrame(benchmark::State& state) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    std::size_t(state.range(1)));
  static std::map<std::size_t, SceneTopology> topologies;
  const std::size_t faces = std::size_t(state.range(0));
  if (!topologies.count(faces)) topologies.emplace(faces, ballTopology(faces));
  const SceneTopology& topology = topologies.at(faces);
  std::string directory =
      (std::filesystem::temp_directory_path() / "softbake-vdb-bench-XXXXXX").string();
  if (!::mkdtemp(directory.data())) throw std::runtime_error("mkdtemp failed");

  VdbOptions options;
  options.voxelSize = 2.0 / 200;
  options.velocity = state.range(2) != 0;
  options.compression = state.range(3) == 0   ? VdbOptions::Compression::Zip
                        : state.range(3) == 1 ? VdbOptions::Compression::Blosc
                                              : VdbOptions::Compression::None;
  VdbSequenceWriter writer(topology, directory, "bench", options);
  Frame frame;
  frame.positions = topology.restPosition;
  frame.velocities.assign(topology.particleCount(), Vec3(0, -1, 0));
  for (auto _ : state) {
    writer.write(frame);
    ++frame.number;
  }
  state.counters["faces"] = double(topology.triangles.size());
  state.counters["MiB/frame"] =
      double(writer.bytesWritten()) / double(state.iterations()) / double(1 << 20);
  std::filesystem::remove_all(directory);
}
BENCHMARK(VdbExportFrame)
    ->ArgNames({"faces", "threads", "vel", "compression"})
    ->ArgsProduct({{10000, 100000}, {1, 2}, {0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace softbake

BENCHMARK_MAIN();
