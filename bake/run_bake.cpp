#include "bake/run_bake.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <regex>
#include <system_error>

#include "bake/bake_report.hpp"
#include "bake/command_errors.hpp"
#include "bake/frame_stats.hpp"
#include "bake/interruption.hpp"
#include "bake/output_budget.hpp"
#include "bake/progress_display.hpp"
#include "bake/run_outputs.hpp"
#include "bake/run_record.hpp"
#include "bake/scene_input.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "exporters/contact_writer.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "exporters/vdb_sequence_writer.hpp"
#include "importers/scene_file.hpp"
#include "output/atomic_file.hpp"
#include "output/cache_format.hpp"
#include "output/cache_writer.hpp"
#include "output/frame_pipeline.hpp"
#include "output/manifest.hpp"
#include "render/egl_context.hpp"
#include "render/png_sequence_renderer.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

void describeSubsteps(const SubstepChoice& choice, IntegratorKind integrator) {
  const double boundMs = choice.boundTimeStep * 1e3, stepMs = choice.timeStep * 1e3;
  if (choice.stableAtAnyStep) {
    char why[160] = "as given";
    if (choice.automatic && choice.closingSpeed > 0)
      std::snprintf(why, sizeof why,
                    "auto, re-chosen every frame from how fast bodies close on each other: "
                    "%.2f m/s now",
                    choice.closingSpeed);
    else if (choice.automatic)
      std::snprintf(why, sizeof why,
                    "auto, re-chosen every frame: no bodies close on each other now");
    std::printf(
        "substeps: %d per frame (%s; %s integrator, stable at any step; time step %.4g ms)\n",
        choice.substeps, why, std::string(integratorName(integrator)).c_str(), stepMs);
  } else if (!std::isfinite(choice.boundTimeStep)) {
    std::printf("substeps: %d per frame (no springs: no stability bound)\n", choice.substeps);
  } else if (choice.automatic) {
    std::printf("substeps: %d per frame (auto: time step %.4g ms, stability bound %.4g ms)\n",
                choice.substeps, stepMs, boundMs);
  } else if (choice.belowBound()) {
    std::fprintf(stderr,
                 "warning: %d substeps give a time step of %.4g ms, above the explicit-Euler "
                 "stability bound of %.4g ms; the run will likely blow up. Use at least %d "
                 "substeps, or 'auto'.\n",
                 choice.substeps, stepMs, boundMs, choice.minimumStableSubsteps);
  } else {
    std::printf("substeps: %d per frame (time step %.4g ms, stability bound %.4g ms)\n",
                choice.substeps, stepMs, boundMs);
  }
}

/// Surfaces that intersect at the start, per pair of bodies (or colliders) and per body with
/// itself, and what the run does with them.
void describeInitialOverlaps(const Simulator& simulator) {
  const InitialOverlaps& overlaps = simulator.initialOverlaps();
  if (overlaps.empty()) return;
  const SceneTopology& topology = simulator.topology();
  // The pairs of surfaces with the most triangle pairs first, and only the first few: a building
  // of 294 parts listed 580 pairs of surfaces, 100 kB on one line.
  constexpr std::size_t kListed = 8;
  std::vector<SurfaceOverlap> largest = overlaps.bySurfaces;
  std::stable_sort(largest.begin(), largest.end(),
                   [](const auto& a, const auto& b) { return a.trianglePairs > b.trianglePairs; });
  std::uint64_t unlistedPairs = 0;
  for (std::size_t k = kListed; k < largest.size(); ++k) unlistedPairs += largest[k].trianglePairs;
  const std::size_t unlisted = largest.size() - std::min(largest.size(), kListed);
  largest.resize(std::min(largest.size(), kListed));
  std::string list;
  for (const SurfaceOverlap& overlap : largest) {
    list += list.empty() ? "" : ", ";
    list += overlap.firstSurface == overlap.secondSurface
                ? cat("'", topology.surfaceName(overlap.firstSurface), "' with itself")
                : cat("'", topology.surfaceName(overlap.firstSurface), "' and '",
                      topology.surfaceName(overlap.secondSurface), "'");
    list += cat(" (", overlap.trianglePairs, " triangle pairs)");
  }
  if (unlisted > 0)
    list += cat(" and ", unlisted, " more pairs of surfaces (", unlistedPairs, " triangle pairs)");
  std::string what;
  switch (topology.settings.collisions.initialOverlap) {
    case InitialOverlapMode::SetAside:
      what = cat("those ", simulator.initiallySetAsidePairs(),
                 " triangle pairs are set aside until they come apart; everything else collides "
                 "(initial_overlap \"set_aside\"; \"separate\" moves bodies apart, \"ignore\" "
                 "glues them)");
      break;
    case InitialOverlapMode::Separate:
      what =
          cat("two bodies are taken apart over the first frames, moved as wholes without "
              "velocity; a body's own ",
              simulator.initiallySetAsidePairs(),
              " pairs are set aside (initial_overlap \"separate\"; \"ignore\" glues them)");
      break;
    case InitialOverlapMode::Ignore:
      what = "those surfaces never collide with each other (initial_overlap \"ignore\")";
      break;
  }
  std::printf("warning: surfaces intersect at the start: %s; %s\n", list.c_str(), what.c_str());
}

/// The scene's size, its substeps and its collision setup, on stdout; with `quiet`, only what
/// may be wrong (too few explicit substeps, surfaces that start inside each other).
void describeRun(const std::string& name, const Simulator& simulator, bool quiet) {
  const SceneTopology& topology = simulator.topology();
  if (quiet) {
    if (!simulator.substeps().stableAtAnyStep && simulator.substeps().belowBound() &&
        !simulator.substeps().automatic)
      describeSubsteps(simulator.substeps(), topology.settings.integrator);
    describeInitialOverlaps(simulator);
    return;
  }
  std::size_t triangles = 0;
  for (const Body& body : topology.bodies) triangles += body.triangleCount;
  std::printf(
      "scene '%s': %zu bodies, %zu particles, %zu triangles, %zu springs; %d frames at %g fps\n",
      name.c_str(), topology.bodies.size(), topology.particleCount(), triangles,
      topology.springs.size(), topology.settings.frames, topology.settings.fps);
  describeSubsteps(simulator.substeps(), simulator.topology().settings.integrator);
  const CollisionSettings& collisions = topology.settings.collisions;
  if (simulator.collides())
    std::printf("collisions: %s broad phase%s, %s\n",
                std::string(broadPhaseName(collisions.broadPhase)).c_str(),
                collisions.broadPhase == BroadPhaseKind::Sbhash
                    ? cat(" (level ", collisions.subdivisionLevels, ")").c_str()
                    : "",
                collisions.response == ResponseMode::None
                    ? "detection only (response \"none\")"
                    : cat(responseModeName(collisions.response), " response").c_str());
  else if (collisions.response == ResponseMode::None)
    std::printf("collisions: detection only, no response\n");
  if (const std::size_t fitted = simulator.initialOverlaps().close.size())
    std::printf(
        "fitted faces: %zu triangle pairs of different surfaces start closer than the "
        "skin; the failsafe keeps them from crossing until they are two skins apart\n",
        fitted);
  describeInitialOverlaps(simulator);
}

/// What a run writes of each frame: a mask of its sinks per frame, all of them in a fresh run, only
/// those whose file is missing in a resumed one.
struct WritePlan {
  std::vector<std::uint64_t> sinksPerFrame;  ///< [frame − 1]
  int firstIncompleteFrame = 1;              ///< frames before it have every file; frames + 1: all
};

/// The plan for the files in `out` now: sequence `s` of `manifest` is sink `s`, and the cache
/// sequence counts a checkpoint frame as written only with its checkpoint.
WritePlan planWrites(const fs::path& out, const Manifest& manifest, int frames, bool everything,
                     const std::optional<CacheLayout>& cache, int checkpointEvery) {
  WritePlan plan;
  plan.sinksPerFrame.assign(std::size_t(frames), 0);
  plan.firstIncompleteFrame = frames + 1;
  for (int frame = frames; frame >= 1; --frame) {
    std::uint64_t& mask = plan.sinksPerFrame[std::size_t(frame - 1)];
    for (std::size_t s = 0; s < manifest.sequences.size(); ++s) {
      const OutputSequence& sequence = manifest.sequences[s];
      std::error_code error;
      bool written =
          !everything &&
          fs::exists(out / sequenceFilePath(sequence, manifest.framePadding, frame), error);
      if (written && cache && sequence.format == "cache" &&
          isCheckpointFrame(frame, checkpointEvery))
        written = fs::exists(cache->checkpointPath(frame), error);
      if (!written) mask |= std::uint64_t(1) << s;
    }
    if (mask != 0) plan.firstIncompleteFrame = frame;
  }
  return plan;
}

struct BakeResult {
  StepStats totals;
  int framesWritten = 0;  ///< frames handed to the writers
  int lastFrame = 0;      ///< the last frame simulated
  int stoppedBy = 0;      ///< the signal that stopped the run early, or 0
  std::string failure;    ///< why the simulation stopped (a blow-up); the frames before it stand
};

/// Simulates frames `firstFrame` + 1 … the last (the simulator starts at `firstFrame`) and hands
/// the writers every frame the plan asks for; stops early, after a whole frame, when a signal asks
/// or the simulation fails. With `recorder`, records every frame for the report.
BakeResult simulateFrames(Simulator& simulator, int firstFrame, const WritePlan& plan,
                          int checkpointEvery, std::optional<std::size_t> cacheSink,
                          FramePipeline& pipeline, ProgressDisplay& progress,
                          const InterruptionGuard& interruption,
                          std::vector<std::uint64_t>& setAsidePairs, FrameStatsRecorder* recorder) {
  const SimulationState& state = simulator.state();
  const SimulationSettings& settings = simulator.topology().settings;
  BakeResult result;
  StepStats& totals = result.totals;
  for (int frame = firstFrame; frame <= settings.frames; ++frame) {
    if (interruption.signal() != 0) {
      result.stoppedBy = interruption.signal();
      break;
    }
    if (frame > firstFrame) {
      const auto start = std::chrono::steady_clock::now();
      try {
        simulator.advanceToFrame(frame);
      } catch (const Error& error) {
        result.failure = error.what();
        break;
      }
      const std::chrono::duration<double> stepTime = std::chrono::steady_clock::now() - start;
      const StepStats& stats = simulator.lastFrameStats();
      if (!setAsidePairs.empty()) setAsidePairs[std::size_t(frame - 1)] = stats.setAsidePairs;
      totals.contacts += stats.contacts;
      totals.planeContacts += stats.planeContacts;
      totals.responses += stats.responses;
      if (recorder) {
        recorder->record(simulator, frame, stepTime.count());
        // Saved before the checkpoint is handed to the cache writer: whatever checkpoint a
        // resumed run finds, the records up to it were saved first.
        if (isCheckpointFrame(frame, checkpointEvery)) recorder->save();
      }
    } else if (recorder && !recorder->has(frame)) {
      recorder->record(simulator, frame, std::nullopt);
    }
    result.lastFrame = frame;
    const std::uint64_t sinks = plan.sinksPerFrame[std::size_t(frame - 1)];
    if (sinks != 0 && (frame > firstFrame || firstFrame == 1)) {
      Frame& out = pipeline.acquire();
      out.number = frame;
      out.time = (frame - 1) / settings.fps;
      std::copy(state.position.begin(), state.position.end(), out.positions.begin());
      std::copy(state.velocity.begin(), state.velocity.end(), out.velocities.begin());
      out.contacts = simulator.contacts();
      out.sinkMask = sinks;
      out.hasCheckpoint =
          cacheSink && ((sinks >> *cacheSink) & 1) && isCheckpointFrame(frame, checkpointEvery);
      if (out.hasCheckpoint) out.checkpoint = simulator.checkpoint();
      // Every writer gets the numbers the cache keeps, so `export` later writes the same files.
      roundToCachePrecision(out);
      pipeline.submit(out);
      ++result.framesWritten;
    }
    progress.update(frame);
  }
  return result;
}

/// The checkpoint interval of `simulator`'s run: the command line's, or the default.
int checkpointInterval(const RunOptions& options, const Simulator& simulator) {
  if (!options.cache) return 0;
  return options.checkpointEvery ? *options.checkpointEvery : defaultCheckpointEvery(simulator);
}

/// Where a resumed run starts: the manifest it continues must describe the same run, and the latest
/// checkpoint before the first incomplete frame (or the scene itself) is restored into `simulator`.
/// Returns the frame the simulator is at.
int restoreForResume(const Manifest& manifest, const WritePlan& plan,
                     const std::optional<CacheLayout>& cache, Simulator& simulator) {
  if (plan.firstIncompleteFrame <= 2 || !cache) return 1;
  std::vector<std::string> skipped;
  const std::optional<DecodedCheckpoint> checkpoint =
      cache->latestCheckpoint(plan.firstIncompleteFrame - 1, &skipped);
  for (const std::string& reason : skipped)
    std::fprintf(stderr, "warning: passing over a damaged checkpoint: %s\n", reason.c_str());
  if (!checkpoint) return 1;
  simulator.restore(checkpoint->checkpoint);
  std::printf("resuming '%s' from the checkpoint of frame %d; frames %d to %d are missing files\n",
              manifest.scene.c_str(), checkpoint->frame, plan.firstIncompleteFrame,
              manifest.framesWritten);
  return checkpoint->frame;
}

/// A resumed run continues a manifest in its folder, of the same run: throws softbake::Error
/// saying what changed otherwise.
void requireSameRun(const RunOptions& options, const nlohmann::ordered_json& record) {
  Manifest previous;
  try {
    previous = readManifest(options.out);
  } catch (const Error& error) {
    throw Error(cat("--resume: ", error.what()));
  }
  const std::vector<std::string> differences = runRecordDifferences(previous.run, record);
  if (!differences.empty())
    throw Error(cat("--resume: ", (options.out / "manifest.json").string(),
                    " records another run; what changed:", listedDifferences(differences),
                    "\nRun again without --resume to start over."));
}

/// One bake, stage by stage: plan (load, check, build; nothing is written), open the outputs,
/// simulate into the cache and the live writers, write from the cache what waits for the whole
/// shot, and report. Each stage reads what the stages before it settled.
class Bake {
 public:
  /// The plan: everything that can refuse the run does so here, before any file is written.
  explicit Bake(const RunOptions& options) : options_(options) {
    if (options.threads > 0)
      threadLimit_.emplace(tbb::global_control::max_allowed_parallelism,
                           std::size_t(options.threads));
    scene_ = loadSceneInput(options.input, options.load);
    applySceneOptions(options.given, scene_);
    if (!options.quiet)
      for (const std::string& note : scene_.notes) std::printf("note: %s\n", note.c_str());
    printWarnings(scene_);
    render_ = renderOptions(scene_.render);
    requireOutputWithin(scene_, render_.width, render_.height, options.maxOutputGib * 0x1p30);

    BuildReport report;
    simulator_ = std::make_unique<Simulator>(buildSceneTopology(scene_.setup, &report));
    if (!options.quiet)
      for (const std::string& note : report.notes) std::printf("note: %s\n", note.c_str());
    name_ = scene_.setup.name;
    frames_ = topology().settings.frames;
    describeRun(name_, *simulator_, options.quiet);
    if (scene_.output.vdb) vdb_ = vdbOptions(options, topology());
    checkpointEvery_ = checkpointInterval(options, *simulator_);
    record_ = runRecord(options, scene_, checkpointEvery_);
    if (options.resume) requireSameRun(options, record_);

    // With the cache, PNG frames are rendered from it once the shot is simulated, the camera
    // framed on all of it, and the point caches, which need every frame in order, are written
    // from it too; without, or when asked, as the frames are simulated.
    if (options.cacheOnly && !options.cache)
      throw Error("--cache-only and --no-cache leave nothing to write");
    afterFromCache_ = options.cache && !options.cacheOnly;
    renderAfter_ = scene_.output.png && afterFromCache_ && !options.renderWhileSimulating;
    if (scene_.output.png && !options.cache && !options.renderWhileSimulating && !options.quiet)
      std::printf(
          "note: --no-cache: PNG frames are rendered as they are simulated, the camera "
          "framed on the first frame\n");
    // The renderer needs an EGL driver: found out now, not when the first frame renders (after
    // the whole simulation, when frames render from the cache).
    if (scene_.output.png && !options.cacheOnly) {
      const EglContext probe(render_.egl);
    }
  }

  /// The remaining stages; returns the exit code.
  int run() {
    openOutputs();
    std::fflush(stdout);  // the scene summary comes before the progress lines on stderr
    ProgressDisplay progress(frames_, options_.quiet);
    const InterruptionGuard interruption;
    try {
      simulate(progress, interruption);
      if (afterFromCache_ && result_.failure.empty() && result_.stoppedBy == 0) {
        progress.finish();
        writeFromCache(interruption);
      }
    } catch (const Error& error) {
      progress.finish();
      try {
        recordEnd(RunStatus::Failed, error.what());
      } catch (const Error&) {
        // The first error is the one to report; the manifest stays as it was.
      }
      writeReportAfterFailure("failed", error.what(), 0, progress.elapsedSeconds());
      throw;
    }
    progress.finish();
    return finish(progress.elapsedSeconds());
  }

 private:
  const SceneTopology& topology() const { return simulator_->topology(); }

  /// Only now is anything written: the folders, the sinks, the manifest of a run in progress;
  /// a resumed run is restored to the checkpoint it continues from.
  void openOutputs() {
    makeDirectories(options_.out);
    // The frames' records of an earlier run in this folder belong to another run; a resumed run
    // continues them.
    const fs::path frameStatsFile = options_.out / "frame_stats.jsonl";
    if (!options_.resume) {
      std::error_code ignored;
      fs::remove(frameStatsFile, ignored);
    }
    if (options_.report) {
      makeDirectories(*options_.report);  // a folder that cannot be made fails before the work
      recorder_.emplace(topology(), frameStatsFile);
    }
    manifest_ = describeScene(topology(), name_, frames_, scene_.output.framePadding);
    manifest_.run = record_;
    manifest_.status = RunStatus::Incomplete;
    manifest_.reason = "in progress, or killed: continue it with --resume";
    OutputOptions liveOutput = scene_.output;
    if (renderAfter_) liveOutput.png = false;
    if (options_.cacheOnly)
      liveOutput.obj = liveOutput.contacts = liveOutput.png = liveOutput.vdb = liveOutput.pc2 =
          liveOutput.mdd = false;
    sinks_ = openSinks(options_, name_, liveOutput, simulator_->sharedTopology(), render_, vdb_,
                       checkpointEvery_, options_.resume, manifest_);
    if (options_.cache) {
      cache_.emplace(options_.out, name_, scene_.output.framePadding);
      cacheSink_ = sinks_.size() - 1;
    }
    const char upAxis = options_.upAxis ? (*options_.upAxis)[0] : 'y';
    pointCaches_ = openPointCacheWriters(name_, liveOutput, simulator_->sharedTopology(),
                                         options_.out, upAxis, manifest_);
    pointCachesNeeded_ =
        !pointCaches_.empty() && (!options_.resume || !pointCachesWritten(options_.out, manifest_));
    // The PNG sequence is listed now, so a killed run's manifest names it too; its renderer is
    // made once the shot's bounds are known.
    rendered_ = manifest_;
    rendered_.sequences.clear();
    if (renderAfter_) openRenderer(render_, options_.resume, rendered_);
    everything_ = manifest_;
    everything_.sequences.insert(everything_.sequences.end(), rendered_.sequences.begin(),
                                 rendered_.sequences.end());

    plan_ =
        planWrites(options_.out, manifest_, frames_, !options_.resume, cache_, checkpointEvery_);
    if (!afterFromCache_ && pointCachesNeeded_) {
      // Written live: they take every frame, from the first (without a cache a run starts there).
      for (std::unique_ptr<FrameSink>& writer : pointCaches_) {
        const std::uint64_t bit = std::uint64_t(1) << sinks_.size();
        for (std::uint64_t& mask : plan_.sinksPerFrame) mask |= bit;
        sinks_.push_back(std::move(writer));
      }
      plan_.firstIncompleteFrame = 1;
    }
    if (options_.resume)
      for (const OutputSequence& sequence : everything_.sequences)
        removeTemporaryFiles(options_.out / fs::path(sequence.pattern).parent_path(), name_);
    firstFrame_ = plan_.firstIncompleteFrame > frames_
                      ? frames_ + 1  // nothing is missing: nothing to simulate
                      : restoreForResume(manifest_, plan_, cache_, *simulator_);
    if (recorder_ && firstFrame_ > 1)
      if (std::string note = recorder_->keepSaved(std::min(firstFrame_, frames_)); !note.empty())
        reportNotes_.push_back(std::move(note));
    if (simulator_->initiallySetAsidePairs() > 0) {
      // A resumed run keeps the counts of the frames it does not simulate again.
      if (options_.resume) everything_.setAsidePairs = readManifest(options_.out).setAsidePairs;
      everything_.setAsidePairs.resize(std::size_t(frames_), 0);
      everything_.setAsidePairs[0] = simulator_->initiallySetAsidePairs();
    }
    everything_.run = record_;
    everything_.status = RunStatus::Incomplete;
    everything_.reason = manifest_.reason;
    everything_.framesComplete =
        planWrites(options_.out, everything_, frames_, !options_.resume, cache_, checkpointEvery_)
            .firstIncompleteFrame -
        1;
    writeManifest(options_.out, everything_);
  }

  /// Rendering from the cache after the simulation: the PNG writer alone.
  std::vector<std::unique_ptr<FrameSink>> openRenderer(const RenderOptions& framing,
                                                       bool keepExisting, Manifest& listed) {
    OutputOptions pngOnly;
    pngOnly.obj = false;
    pngOnly.png = true;
    pngOnly.framePadding = scene_.output.framePadding;
    RunOptions noCache = options_;
    noCache.cache = false;
    return openSinks(noCache, name_, pngOnly, simulator_->sharedTopology(), framing, vdb_, 0,
                     keepExisting, listed);
  }

  /// The frames simulated into the cache and the live writers.
  void simulate(ProgressDisplay& progress, const InterruptionGuard& interruption) {
    FramePipeline pipeline(std::move(sinks_), topology().particleCount());
    result_ = simulateFrames(*simulator_, firstFrame_, plan_, checkpointEvery_, cacheSink_,
                             pipeline, progress, interruption, everything_.setAsidePairs,
                             recorder_ ? &*recorder_ : nullptr);
    pipeline.finish();
    bytesWritten_ = pipeline.bytesWritten();
  }

  /// What waits for the whole shot, written from the cache: the PNG frames, framed on all of it,
  /// and the point caches.
  void writeFromCache(const InterruptionGuard& interruption) {
    std::vector<std::unique_ptr<FrameSink>> after;
    std::vector<std::uint64_t> masks(std::size_t(frames_), 0);
    if (renderAfter_) {
      const WritePlan renderPlan =
          planWrites(options_.out, rendered_, frames_, !options_.resume, std::nullopt, 0);
      if (renderPlan.firstIncompleteFrame <= frames_) {
        RenderOptions framed = render_;
        framed.shotBounds = cache_->shotBounds(frames_);
        Manifest unused;
        after = openRenderer(framed, /*keepExisting=*/true, unused);
        masks = renderPlan.sinksPerFrame;
      }
    }
    if (pointCachesNeeded_)
      for (std::unique_ptr<FrameSink>& writer : pointCaches_) {
        const std::uint64_t bit = std::uint64_t(1) << after.size();
        for (std::uint64_t& mask : masks) mask |= bit;
        after.push_back(std::move(writer));
      }
    if (after.empty()) return;
    FramePipeline pipeline(std::move(after), topology().particleCount());
    ProgressDisplay writing(frames_, options_.quiet);
    const int last =
        softbake::writeFromCache(*cache_, 1, frames_, masks, pipeline, writing, &interruption);
    writing.finish();
    if (last < frames_) {
      result_.stoppedBy = interruption.signal();
      result_.lastFrame = last;
    }
    bytesWritten_ += pipeline.bytesWritten();
  }

  /// How the run ended, in the manifest, with how far it got.
  void recordEnd(RunStatus status, std::string reason) {
    everything_.status = status;
    everything_.reason = std::move(reason);
    everything_.framesComplete =
        planWrites(options_.out, everything_, frames_, false, cache_, checkpointEvery_)
            .firstIncompleteFrame -
        1;
    writeManifest(options_.out, everything_);
  }

  /// The end: the manifest's status, the summary, the report. Throws for a failed simulation;
  /// returns the exit code of an interrupted or complete run.
  int finish(double seconds) {
    if (!result_.failure.empty()) {
      recordEnd(RunStatus::Failed, result_.failure);
      writeReportAfterFailure("failed", result_.failure, result_.lastFrame + 1, seconds);
      throw SimulationFailure(result_.failure);
    }
    if (result_.stoppedBy != 0) {
      const std::string reason =
          cat("interrupted by ", signalName(result_.stoppedBy), " after frame ", result_.lastFrame);
      recordEnd(RunStatus::Incomplete, reason);
      writeReportAfterFailure("interrupted", reason, 0, seconds);
      std::fflush(stdout);
      std::fprintf(
          stderr,
          "\nsoftbake: interrupted by %s after frame %d of %d; frames 1 to %d are "
          "complete. Continue with:\n  %s --resume\n",
          signalName(result_.stoppedBy), result_.lastFrame, frames_, everything_.framesComplete,
          options_.commandLine.empty() ? "softbake run ..." : options_.commandLine.c_str());
      return interruptedExitCode(result_.stoppedBy);
    }
    recordEnd(RunStatus::Complete, "");
    printSummary(seconds);
    writeReport("complete", "", 0, seconds);
    return 0;
  }

  void printSummary(double seconds) const {
    const double steps = double(simulator_->stepsTaken());
    if (options_.resume)
      std::printf("resumed: wrote %d missing frames (%s) to %s in %.2f s\n", result_.framesWritten,
                  formatBytes(bytesWritten_).c_str(), options_.out.string().c_str(), seconds);
    else
      // Frame 1 is the initial state: the rate counts the frames that were simulated.
      std::printf(
          "wrote %d frames (%s) to %s in %.2f s: %.1f simulated frames/s, %.0f steps, %.0f "
          "steps/s\n",
          frames_, formatBytes(bytesWritten_).c_str(), options_.out.string().c_str(), seconds,
          seconds > 0 ? (frames_ - 1) / seconds : 0.0, steps, seconds > 0 ? steps / seconds : 0.0);
    if (simulator_->collides())
      std::printf(
          "contacts over all substeps: %zu (particle %zu, corner %zu, edge pushes %zu); "
          "plane contacts %zu\n",
          result_.totals.contacts, result_.totals.responses.particleResponses,
          result_.totals.responses.cornerResponses, result_.totals.responses.edgePushes,
          result_.totals.planeContacts);
    else if (!topology().planes.empty())
      std::printf("plane contacts over all substeps: %zu\n", result_.totals.planeContacts);
    if (!everything_.setAsidePairs.empty())
      std::printf(
          "initial overlaps: %zu triangle pairs set aside at the start, %llu still at frame %d "
          "(per frame in the manifest's set_aside_pairs)\n",
          simulator_->initiallySetAsidePairs(),
          static_cast<unsigned long long>(everything_.setAsidePairs.back()), frames_);
    for (const OutputSequence& sequence : everything_.sequences)
      std::printf("%s sequence: %s\n", sequence.format.c_str(),
                  (options_.out / sequence.pattern).string().c_str());
    std::printf("manifest: %s\n", (options_.out / "manifest.json").string().c_str());
  }

  /// The report, for as many frames as were simulated, however the run ended.
  void writeReport(const std::string& status, const std::string& failure, int failedFrame,
                   double seconds) {
    if (!recorder_) return;
    recorder_->save();
    const SceneTopology& topology = this->topology();
    BakeReport contents;
    contents.scene = name_;
    contents.input = options_.input;
    contents.out = options_.out;
    contents.frames = frames_;
    contents.fps = topology.settings.fps;
    contents.integrator = std::string(integratorName(topology.settings.integrator));
    const SubstepChoice& substeps = simulator_->substeps();
    contents.substeps = substeps.automatic ? "auto" : std::to_string(substeps.substeps);
    // "auto" of the integrators stable at any step stops at kMaxAutoSubsteps, unless XPBD's own
    // floor is above it.
    if (substeps.automatic && substeps.stableAtAnyStep &&
        !(topology.settings.integrator == IntegratorKind::Xpbd &&
          substeps.minimumStableSubsteps >= kMaxAutoSubsteps))
      contents.substepCap = kMaxAutoSubsteps;
    for (const Body& body : topology.bodies)
      contents.bodies.push_back(
          {body.name, body.closed, body.restVolume, body.material.bulkModulus > 0});
    contents.records = recorder_->records();
    contents.wallSeconds = seconds;
    contents.status = status;
    contents.failure = failure;
    contents.failedFrame = failedFrame;
    contents.notes = reportNotes_;
    for (const OutputSequence& sequence : everything_.sequences)
      if (sequence.format == "png")
        for (int frame = 1; frame <= frames_; ++frame) {
          const fs::path png =
              options_.out / sequenceFilePath(sequence, everything_.framePadding, frame);
          std::error_code error;
          if (fs::is_regular_file(png, error)) contents.pngFrames.emplace_back(frame, png);
        }
    writeBakeReport(*options_.report, contents);
    std::printf("report: %s\n", (*options_.report / "index.html").string().c_str());
  }

  /// After a failure, the failure is what the run exits with; a report that cannot be written too
  /// is a warning.
  void writeReportAfterFailure(const std::string& status, const std::string& failure,
                               int failedFrame, double seconds) {
    try {
      writeReport(status, failure, failedFrame, seconds);
    } catch (const Error& error) {
      std::fprintf(stderr, "warning: the report could not be written: %s\n", error.what());
    } catch (const fs::filesystem_error& error) {
      std::fprintf(stderr, "warning: the report could not be written: %s\n", error.what());
    }
  }

  const RunOptions& options_;
  std::optional<tbb::global_control> threadLimit_;  // first made, last gone
  // The plan.
  SceneFile scene_;
  RenderOptions render_;
  std::unique_ptr<Simulator> simulator_;
  std::string name_;
  int frames_ = 0;
  std::optional<VdbOptions> vdb_;
  int checkpointEvery_ = 0;
  nlohmann::ordered_json record_;
  bool afterFromCache_ = false, renderAfter_ = false;
  // The outputs.
  std::optional<FrameStatsRecorder> recorder_;
  std::vector<std::string> reportNotes_;
  /// The live sinks' sequences; those rendered from the cache after the simulation; both, as the
  /// manifest lists them.
  Manifest manifest_, rendered_, everything_;
  std::vector<std::unique_ptr<FrameSink>> sinks_, pointCaches_;
  std::optional<CacheLayout> cache_;
  std::optional<std::size_t> cacheSink_;
  bool pointCachesNeeded_ = false;
  WritePlan plan_;
  int firstFrame_ = 1;
  // The simulation.
  BakeResult result_;
  std::uint64_t bytesWritten_ = 0;
};

}  // namespace

int runBake(const RunOptions& options) {
  return reportingErrors([&] { return Bake(options).run(); });
}

}  // namespace softbake
