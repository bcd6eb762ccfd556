#include "cli/bench_command.hpp"

#include <stdlib.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "bake/command_errors.hpp"
#include "bake/run_outputs.hpp"
#include "bake/scene_input.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "exporters/vdb_sequence_writer.hpp"
#include "output/atomic_file.hpp"
#include "output/cache_writer.hpp"
#include "render/png_sequence_renderer.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double milliseconds(std::int64_t nanoseconds) {
  return double(nanoseconds) * 1e-6;
}

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Spread {
  double median = 0, p95 = 0;
};

/// Median and 95th percentile (nearest rank) of `values`, which it reorders.
Spread spread(std::vector<double>& values) {
  if (values.empty()) return {};
  const auto at = [&](double fraction) {
    const std::size_t rank =
        std::min(values.size() - 1, std::size_t(fraction * double(values.size())));
    std::nth_element(values.begin(), values.begin() + long(rank), values.end());
    return values[rank];
  };
  return {at(0.5), at(0.95)};
}

double peakResidentMiB() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

/// One writer's cost per frame, measured on the bench thread.
struct ExportTiming {
  std::unique_ptr<FrameSink> sink;
  double seconds = 0;
  int frames = 0;
};

/// A temporary folder for the exports, removed with everything in it.
class ScratchFolder {
 public:
  ScratchFolder() {
    std::string pattern = (fs::temp_directory_path() / "softbake-bench-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw Error("cannot create a temporary folder for exports");
    path_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// What the measured loop records per step; summarised after, so the loop only records.
struct StepRecord {
  std::vector<StageTimes> times;
  std::vector<std::uint32_t> pairs, contacts;
  std::vector<int> frames;     ///< the frame each step computes
  double framesSimulated = 0;  ///< whole frames, plus the finished part of a last partial one
  std::uint64_t solverIterations = 0;  ///< the implicit integrator's CG iterations, all steps
  std::uint64_t solverPhases = 0;      ///< and the phases of its parallel regions
  std::uint64_t failsafePasses = 0;    ///< the failsafe's detection passes, all steps
  std::uint64_t frozenSubsteps = 0;    ///< substeps that reached the failsafe's last resort
  std::uint64_t frozenBodies = 0;      ///< and the bodies it put back at their start, at rest
  std::uint64_t bodiesMovedAsOne = 0;  ///< and the bodies it moved as one from their start
  /// The largest |V/V_rest − 1| of any closed body at the end of any frame: how round the bodies
  /// stayed, the measure peers are compared at.
  double maxVolumeError = 0;
  double simulationSeconds = 0;
};

/// The simulation cache's writer (frames and checkpoints, fsync'ed), then the OBJ, VDB and PNG
/// writers, each timed on the bench thread.
std::vector<ExportTiming> openExports(const Simulator& simulator, const fs::path& folder,
                                      const std::string& name, int checkpointEvery) {
  std::vector<ExportTiming> exports;
  exports.push_back(
      {std::make_unique<CacheWriter>(folder, name, 4, simulator.topology().settings.frames,
                                     checkpointEvery, simulator.topology().particleCount())});
  exports.push_back(
      {std::make_unique<ObjSequenceWriter>(simulator.sharedTopology(), folder, name)});
  VdbOptions vdb;
  vdb.fps = simulator.topology().settings.fps;
  exports.push_back({std::make_unique<VdbSequenceWriter>(simulator.topology(), folder, name, vdb)});
  exports.push_back({std::make_unique<PngSequenceRenderer>(simulator.sharedTopology(), folder, name,
                                                           RenderOptions{})});
  return exports;
}

/// Runs frames 2, 3, … as `run` does, each with the substeps its integrator chooses for it, until
/// frame `lastFrame`, or with `stepLimit` until that many substeps; after each frame's last
/// substep, every export writes it.
StepRecord runMeasuredSteps(Simulator& simulator, int lastFrame,
                            std::optional<std::size_t> stepLimit,
                            std::vector<ExportTiming>& exports, int checkpointEvery) {
  const double fps = simulator.topology().settings.fps;
  StepRecord record;
  const std::size_t expected =
      stepLimit ? *stepLimit
                : std::size_t(lastFrame - 1) * std::size_t(simulator.substeps().substeps);
  record.times.reserve(expected);
  record.pairs.reserve(expected);
  record.contacts.reserve(expected);
  record.frames.reserve(expected);
  Frame frame;
  ForceBuffers volumes(simulator.topology());  // the frame's volumes, outside the timed steps
  simulator.measureStages(true);
  for (int frameNumber = 2; stepLimit || frameNumber <= lastFrame; ++frameNumber) {
    simulator.beginFrame();
    const int substeps = simulator.substeps().substeps;
    int substep = 0;
    for (; substep < substeps && !(stepLimit && record.times.size() == *stepLimit); ++substep) {
      const Clock::time_point start = Clock::now();
      const FailsafeStats before = simulator.lastFrameStats().failsafe;
      simulator.step(frameNumber);
      record.simulationSeconds += secondsSince(start);
      record.times.push_back(simulator.lastStepTimes());
      record.pairs.push_back(std::uint32_t(simulator.lastStepCandidatePairs()));
      record.contacts.push_back(std::uint32_t(simulator.contacts().size()));
      record.frames.push_back(frameNumber);
      if (const auto solve = simulator.lastSolve()) {
        record.solverIterations += solve->stepIterations;
        record.solverPhases += solve->stepPhases;
      }
      const FailsafeStats& after = simulator.lastFrameStats().failsafe;
      record.failsafePasses += after.passes - before.passes;
      record.frozenSubsteps += after.frozen - before.frozen;
      record.frozenBodies += after.frozenBodies - before.frozenBodies;
      record.bodiesMovedAsOne += after.bodiesMovedAsOne - before.bodiesMovedAsOne;
    }
    record.framesSimulated += double(substep) / substeps;
    if (substep < substeps) break;  // the step limit ended the run inside this frame
    simulator.endFrame();
    computeVolumes(simulator.topology(), simulator.state(), volumes);
    for (std::size_t b = 0; b < simulator.topology().bodies.size(); ++b) {
      const Body& body = simulator.topology().bodies[b];
      if (body.closed && body.restVolume > 0)
        record.maxVolumeError =
            std::max(record.maxVolumeError, std::abs(volumes.bodyVolume[b] / body.restVolume - 1));
    }
    if (!exports.empty()) {
      frame.number = frameNumber;
      frame.time = (frameNumber - 1) / fps;
      frame.positions = simulator.state().position;
      frame.velocities = simulator.state().velocity;
      frame.contacts = simulator.contacts();
      frame.hasCheckpoint = isCheckpointFrame(frameNumber, checkpointEvery);
      if (frame.hasCheckpoint) frame.checkpoint = simulator.checkpoint();
      for (ExportTiming& e : exports) {
        const Clock::time_point exportStart = Clock::now();
        e.sink->write(frame);
        e.seconds += secondsSince(exportStart);
        ++e.frames;
      }
    }
  }
  // A writer may still be finishing its last frame (the PNG encoder overlaps the next render).
  for (ExportTiming& e : exports) {
    const Clock::time_point finishStart = Clock::now();
    e.sink->finish();
    e.seconds += secondsSince(finishStart);
  }
  return record;
}

/// Per stage: median and p95 over the steps, and the share of the total. Returns the whole
/// step's spread.
Spread printStages(const StepRecord& record) {
  const std::size_t steps = record.times.size();
  std::printf("  %-13s %10s %10s %7s\n", "stage", "median ms", "p95 ms", "share");
  std::int64_t allStages = 0;
  for (const StageTimes& t : record.times) allStages += t.total();
  std::vector<double> values(steps);
  for (int stage = 0; stage < kStageCount; ++stage) {
    std::int64_t sum = 0;
    for (std::size_t s = 0; s < steps; ++s) {
      values[s] = milliseconds(record.times[s].nanoseconds[stage]);
      sum += record.times[s].nanoseconds[stage];
    }
    const Spread stageSpread = spread(values);
    std::printf("  %-13s %10.4f %10.4f %6.1f%%\n", stageName(Stage(stage)), stageSpread.median,
                stageSpread.p95, allStages > 0 ? 100.0 * double(sum) / double(allStages) : 0.0);
  }
  for (std::size_t s = 0; s < steps; ++s) values[s] = milliseconds(record.times[s].total());
  const Spread step = spread(values);
  std::printf("  %-13s %10.4f %10.4f\n", "step", step.median, step.p95);
  return step;
}

/// Contacts and pairs per step, and each export's cost per frame. Returns the contacts per step.
double printContactsAndExports(const StepRecord& record, const std::vector<ExportTiming>& exports) {
  const std::size_t steps = record.times.size();
  double contactSum = 0, pairSum = 0;
  std::uint32_t contactMax = 0;
  for (std::size_t s = 0; s < steps; ++s) {
    contactSum += record.contacts[s];
    pairSum += record.pairs[s];
    contactMax = std::max(contactMax, record.contacts[s]);
  }
  const double contactsPerStep = contactSum / double(steps);
  std::printf("  contacts per step: mean %.1f, max %u; broad-phase pairs per step: mean %.1f\n",
              contactsPerStep, contactMax, pairSum / double(steps));
  std::printf(
      "  failsafe passes per step: mean %.1f; substeps that reached its last resort: %llu "
      "(bodies put back at rest: %llu; moved as one: %llu)\n",
      double(record.failsafePasses) / double(steps),
      static_cast<unsigned long long>(record.frozenSubsteps),
      static_cast<unsigned long long>(record.frozenBodies),
      static_cast<unsigned long long>(record.bodiesMovedAsOne));
  for (const ExportTiming& e : exports) {
    const double perFrame = e.frames > 0 ? e.seconds / e.frames : 0;
    std::printf("  export %-4s %8.2f ms per frame over %d frames", e.sink->name(), perFrame * 1e3,
                e.frames);
    if (std::string(e.sink->name()) == "obj" && e.seconds > 0)
      std::printf(", %.0f MB/s", double(e.sink->bytesWritten()) / e.seconds / 1e6);
    std::printf("\n");
  }
  return contactsPerStep;
}

/// One CSV row per step.
void appendCsvRows(std::string& csv, const std::string& broadPhase, const StepRecord& record) {
  for (std::size_t s = 0; s < record.times.size(); ++s) {
    const StageTimes& t = record.times[s];
    csv += cat(broadPhase, ",", s + 1, ",", record.frames[s]);
    for (int stage = 0; stage < kStageCount; ++stage)
      csv += cat(",", milliseconds(t.nanoseconds[stage]));
    csv += cat(",", milliseconds(t.total()), ",", record.pairs[s], ",", record.contacts[s], "\n");
  }
}

int bench(const BenchOptions& options) {
  std::optional<tbb::global_control> threadLimit;
  if (options.threads > 0)
    threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(options.threads));
  // What TBB will use: the limit just set, or all cores.
  const int threads =
      int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

  const SceneFile loaded = loadSceneInput(options.input, options.load);
  printWarnings(loaded);
  // One run per broad phase given, each landing as run's --broadphase lands; none: the scene's.
  std::vector<GivenOptions> runs;
  if (const auto list = options.given.find("broadphase"); list != options.given.end()) {
    for (const nlohmann::json& broadPhase : *list) {
      runs.push_back(options.given);
      runs.back()["broadphase"] = broadPhase;
    }
  } else {
    runs.push_back(options.given);
  }

  // One column per stage, named as the stages name themselves, so a new stage cannot leave the
  // header a column short.
  std::string csv = "broadphase,step,frame,";
  for (int stage = 0; stage < kStageCount; ++stage) csv += cat(stageName(Stage(stage)), "_ms,");
  csv += "step_ms,pairs,contacts\n";
  std::optional<ScratchFolder> scratch;
  if (options.withExports && options.out.empty()) scratch.emplace();
  const fs::path exportFolder = scratch ? scratch->path() : options.out;

  for (const GivenOptions& given : runs) {
    SceneFile scene = loaded;
    SimulationSettings& settings = scene.setup.settings;
    applySceneOptions(given, scene);
    const std::string broadPhase(broadPhaseName(settings.collisions.broadPhase));

    Simulator simulator(buildSceneTopology(scene.setup));
    const SceneTopology& topology = simulator.topology();
    std::size_t faces = 0;
    for (const Body& body : topology.bodies) faces += body.triangleCount;
    const SubstepChoice& substeps = simulator.substeps();
    if (options.steps ? *options.steps < 1 : settings.frames < 2)
      throw Error("nothing to run: give --steps or at least 2 --frames");
    std::optional<std::size_t> stepLimit;
    if (options.steps) stepLimit = std::size_t(*options.steps);
    const bool rechosen = substeps.stableAtAnyStep && substeps.automatic;
    std::printf(
        "bench '%s': %zu faces, %zu bodies, %zu particles; %s, steps of %.4g ms (%d per frame%s), "
        "%s broad phase%s, %d threads%s, %s integrator\n",
        scene.setup.name.c_str(), faces, topology.bodies.size(), topology.particleCount(),
        stepLimit ? cat(*stepLimit, " steps").c_str() : cat(settings.frames - 1, " frames").c_str(),
        substeps.timeStep * 1e3, substeps.substeps,
        rechosen ? " at the start, chosen again every frame" : "", broadPhase.c_str(),
        settings.collisions.pairCache ? " with the pair cache" : " every step", threads,
        options.warmupSteps ? cat(", after ", options.warmupSteps, " warm-up steps").c_str() : "",
        std::string(integratorName(settings.integrator)).c_str());
    std::fflush(stdout);

    std::vector<ExportTiming> exports;
    const int checkpointEvery = defaultCheckpointEvery(simulator);
    if (options.withExports)
      exports = openExports(simulator, exportFolder, scene.setup.name, checkpointEvery);
    for (long s = 0; s < options.warmupSteps; ++s) simulator.step(1);
    const StepRecord record =
        runMeasuredSteps(simulator, settings.frames, stepLimit, exports, checkpointEvery);
    const std::size_t steps = record.times.size();

    const Spread step = printStages(record);
    const double contactsPerStep = printContactsAndExports(record, exports);
    const double stepsPerSecond = double(steps) / record.simulationSeconds;
    const double peak = peakResidentMiB();
    std::printf(
        "scene=%s faces=%zu broadphase=%s pair_cache=%d threads=%d warmup=%ld steps=%zu "
        "steps_per_s=%.1f frames_per_s=%.2f "
        "median_step_ms=%.4f p95_step_ms=%.4f contacts_per_step=%.1f peak_rss_mb=%.1f "
        "bytes_per_face=%.0f integrator=%s solver_iterations_per_step=%.1f "
        "solver_phases_per_step=%.1f "
        "max_volume_error=%.4f set_aside_start=%zu set_aside_end=%zu fitted_start=%zu "
        "fitted_end=%zu "
        "failsafe_passes_per_step=%.1f frozen_substeps=%llu frozen_bodies=%llu moved_as_one=%llu\n",
        scene.setup.name.c_str(), faces, broadPhase.c_str(), int(settings.collisions.pairCache),
        threads, options.warmupSteps, steps, stepsPerSecond,
        record.framesSimulated / record.simulationSeconds, step.median, step.p95, contactsPerStep,
        peak, peak * 1048576.0 / double(faces),
        std::string(integratorName(settings.integrator)).c_str(),
        double(record.solverIterations) / double(steps),
        double(record.solverPhases) / double(steps), record.maxVolumeError,
        simulator.initiallySetAsidePairs(), simulator.setAsidePairs().size(),
        simulator.initialOverlaps().close.size(), simulator.fittedPairs().size(),
        double(record.failsafePasses) / double(steps),
        static_cast<unsigned long long>(record.frozenSubsteps),
        static_cast<unsigned long long>(record.frozenBodies),
        static_cast<unsigned long long>(record.bodiesMovedAsOne));
    std::fflush(stdout);
    if (options.csv) appendCsvRows(csv, broadPhase, record);
  }
  if (options.csv) {
    writeFileAtomically(*options.csv, csv);
    std::printf("csv: %s\n", options.csv->string().c_str());
  }
  return 0;
}

}  // namespace

int benchCommand(const BenchOptions& options) {
  return reportingErrors([&] { return bench(options); });
}

}  // namespace softbake
