/// Times every stage of one substep separately, and the whole Simulator::step, on icosphere
/// scenes of about 1k, 10k, 100k and 1M faces at 1 and 2 TBB threads.
///
/// Built twice: core_stages_bench against the float core and core_stages_bench_double against
/// softbake_core_double, so the two programs time the same code with Scalar = float and double.
/// Arguments are {faces, threads}; items/s counts faces. How to run: bench/results/README.md.

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/scene_sizes.hpp"
#include "core/collision/plane_contact.hpp"
#include "core/dynamics/forces.hpp"
#include "core/dynamics/integrator.hpp"
#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/scene/material.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"
#include "core/simulator.hpp"

namespace softbake {
namespace {

using bench::kSceneSizes;
using bench::SceneSize;

/// Substeps run before timing, so springs are stretched, the gas is pressed and the balls rest
/// on the ground: the stages then see a state from a real run, not the rest shape.
constexpr int kWarmUpSubsteps = 8;

/// The stages that change the particle state are put back to their starting state this often
/// (with the timer paused), so the state stays one a real run could reach.
constexpr int kRestorePeriod = 64;

/// The warmed-up simulator of each size, built once per process and copied by each benchmark.
const Simulator& preparedSimulator(int faces) {
  static std::map<int, Simulator> cache;
  if (auto it = cache.find(faces); it != cache.end()) return it->second;
  Simulator simulator(buildSceneTopology(bench::ballsScene(bench::sceneSize(faces))));
  if (simulator.topology().triangles.size() != std::size_t(faces))
    throw std::runtime_error("scene has " + std::to_string(simulator.topology().triangles.size()) +
                             " faces, not " + std::to_string(faces));
  for (int s = 0; s < kWarmUpSubsteps; ++s) simulator.step(1);
  return cache.emplace(faces, std::move(simulator)).first->second;
}

void setCounters(benchmark::State& state, const SceneTopology& topology) {
  state.SetItemsProcessed(state.iterations() * std::int64_t(topology.triangles.size()));
  state.counters["faces"] = double(topology.triangles.size());
  state.counters["particles"] = double(topology.particleCount());
  state.counters["springs"] = double(topology.springs.size());
  state.counters["contacts"] = 0;  // every run needs every counter for the CSV reporter
}

/// Copies the prepared simulator of the benchmark's size under a TBB limit of range(1) threads;
/// the limit lasts as long as this object. The stage benchmarks drive a copy of its state and
/// buffers by hand; BM_Step runs the copied simulator.
struct StageRun {
  explicit StageRun(const benchmark::State& state)
      : threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1))),
        simulator(preparedSimulator(int(state.range(0))).sharedTopology(),
                  preparedSimulator(int(state.range(0))).state()),
        topology(simulator.topology()),
        particles(simulator.state()),
        forces(topology),
        substepStart(particles.position) {}
  /// The forces stage, in the simulator's order.
  void computeForces() {
    computeSpringForces(topology, particles, forces);
    computeVolumes(topology, particles, forces);
    computePressureForces(topology, particles, forces);
  }

  tbb::global_control threads;
  Simulator simulator;
  const SceneTopology& topology;
  SimulationState particles;
  ForceBuffers forces;
  std::vector<Vec3> substepStart;
};

void BM_SpringForces(benchmark::State& state) {
  StageRun run(state);
  for (auto _ : state) {
    computeSpringForces(run.topology, run.particles, run.forces);
    benchmark::ClobberMemory();
  }
  setCounters(state, run.topology);
}

void BM_Volumes(benchmark::State& state) {
  StageRun run(state);
  for (auto _ : state) {
    computeVolumes(run.topology, run.particles, run.forces);
    benchmark::DoNotOptimize(run.forces.bodyVolume.data());
    benchmark::ClobberMemory();
  }
  setCounters(state, run.topology);
}

void BM_PressureForces(benchmark::State& state) {
  StageRun run(state);
  computeVolumes(run.topology, run.particles, run.forces);
  for (auto _ : state) {
    computePressureForces(run.topology, run.particles, run.forces);
    benchmark::ClobberMemory();
  }
  setCounters(state, run.topology);
}

void BM_Integrate(benchmark::State& state) {
  StageRun run(state);
  const Scalar dt = Scalar(run.simulator.substeps().timeStep);
  run.computeForces();
  const SimulationState start = run.particles;
  int sinceRestore = 0;
  for (auto _ : state) {
    if (++sinceRestore == kRestorePeriod) {
      state.PauseTiming();
      run.particles = start;
      sinceRestore = 0;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(
        integrate(run.topology, run.forces, dt, run.particles, run.substepStart));
    benchmark::ClobberMemory();
  }
  setCounters(state, run.topology);
}

/// Every call sees the state integrate() leaves: the particles in contact are put back before
/// each call (timed; they are ~2% of the particles), the others were never moved.
void BM_PlaneContacts(benchmark::State& state) {
  StageRun run(state);
  const SceneTopology& topology = run.topology;
  SimulationState& particles = run.particles;
  run.computeForces();
  integrate(topology, run.forces, Scalar(run.simulator.substeps().timeStep), particles,
            run.substepStart);
  const SimulationState start = particles;
  std::vector<Index> touched;
  for (Index i = 0; i < particles.particleCount(); ++i)
    for (const PlaneCollider& plane : topology.planes)
      if (plane.normal.dot(particles.position[i] - plane.point) < topology.settings.skin) {
        touched.push_back(i);
        break;
      }
  std::size_t contacts = 0;
  for (auto _ : state) {
    for (Index i : touched) {
      particles.position[i] = start.position[i];
      particles.velocity[i] = start.velocity[i];
    }
    contacts += resolvePlaneContacts(topology, run.substepStart, particles);
    benchmark::ClobberMemory();
  }
  setCounters(state, topology);
  state.counters["contacts"] =
      state.iterations() ? double(contacts) / double(state.iterations()) : 0.0;
}

void BM_Step(benchmark::State& state) {
  StageRun run(state);
  try {
    for (auto _ : state) run.simulator.step(1);
  } catch (const Error& error) {
    state.SkipWithError(error.what());
  }
  setCounters(state, run.topology);
}

void sizesAndThreads(benchmark::internal::Benchmark* b) {
  b->ArgNames({"faces", "threads"});
  for (const SceneSize& size : kSceneSizes)
    for (int threads : {1, 2}) b->Args({size.faces, threads});
  b->UseRealTime()->Unit(benchmark::kMicrosecond);
  // On a shared machine the fastest repetition is the one least disturbed by other work.
  b->ComputeStatistics(
      "min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); });
}

BENCHMARK(BM_SpringForces)->Apply(sizesAndThreads);
BENCHMARK(BM_Volumes)->Apply(sizesAndThreads);
BENCHMARK(BM_PressureForces)->Apply(sizesAndThreads);
BENCHMARK(BM_Integrate)->Apply(sizesAndThreads);
BENCHMARK(BM_PlaneContacts)->Apply(sizesAndThreads);
BENCHMARK(BM_Step)->Apply(sizesAndThreads);

}  // namespace
}  // namespace softbake

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("scalar", sizeof(softbake::Scalar) == 8 ? "double" : "float");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
