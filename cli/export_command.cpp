#include "cli/export_command.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "bake/command_errors.hpp"
#include "bake/progress_display.hpp"
#include "bake/run_outputs.hpp"
#include "bake/run_record.hpp"
#include "bake/scene_input.hpp"
#include "core/error.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/text.hpp"
#include "output/cache_writer.hpp"
#include "output/frame_pipeline.hpp"

namespace softbake {

namespace {

struct FrameRange {
  int first = 1, last = 1;
};

/// "A:B" or "A" within 1 … `available`; empty: all of them.
FrameRange parseFrameRange(const std::string& text, int available) {
  if (text.empty()) return {1, available};
  int first = 0, last = 0;
  char colon = 0, extra = 0;
  const int read = std::sscanf(text.c_str(), "%d%c%d%c", &first, &colon, &last, &extra);
  if (read == 1)
    last = first;
  else if (read != 3 || colon != ':')
    throw Error(cat("--frames: expected A:B or A, got '", text, "'"));
  if (first < 1 || last < first || last > available)
    throw Error(cat("--frames ", text, ": the cache holds frames 1 to ", available));
  return {first, last};
}

int exportFrames(const ExportOptions& options) {
  if (!options.obj && !options.vdb && !options.png && !options.contacts && !options.pc2 &&
      !options.mdd && !options.all)
    throw Error(
        "export: name the outputs to write: --obj, --vdb, --png, --contacts, --pc2, --mdd, or "
        "--all for those "
        "the run asked for");
  std::optional<tbb::global_control> threadLimit;
  if (options.threads > 0)
    threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(options.threads));

  Manifest manifest = readManifest(options.out);
  const std::string source = (options.out / "manifest.json").string();
  RunOptions run = runOptionsFromRecord(manifest.run, options.out, source);
  if (!run.cache)
    throw Error(cat(source, ": the run was made with --no-cache: there is nothing to export from"));

  // The run's scene, rebuilt as it was: the files it read must not have changed since.
  SceneFile scene = loadSceneInput(run.input, run.load);
  applySceneOptions(run.given, scene);
  const int checkpointEvery = recordedCheckpointInterval(manifest.run);
  const std::vector<std::string> differences =
      runRecordDifferences(manifest.run, runRecord(run, scene, checkpointEvery));
  if (!differences.empty())
    throw Error(cat("export: the run in ", source,
                    " was made from other inputs:", listedDifferences(differences)));
  const FrameRange range = parseFrameRange(options.frames, manifest.framesWritten);

  if (!options.all) {
    scene.output.obj = options.obj;
    scene.output.contacts = options.contacts;
    scene.output.png = options.png;
    scene.output.vdb = options.vdb;
    scene.output.pc2 = options.pc2;
    scene.output.mdd = options.mdd;
  }
  const bool pointCaches = scene.output.pc2 || scene.output.mdd;
  if (pointCaches && range.first != 1)
    throw Error(
        "export: point caches hold every frame: export --pc2 and --mdd without --frames, "
        "or from frame 1");
  run.cache = false;  // read, not written
  const std::shared_ptr<const SceneTopology> topology =
      std::make_shared<const SceneTopology>(buildSceneTopology(scene.setup));
  if (options.contactsView) scene.render.contactsView = options.contactsView;  // after the check
  const RenderOptions render = renderOptions(scene.render);
  std::optional<VdbOptions> vdb;
  if (scene.output.vdb) vdb = vdbOptions(run, *topology);
  const CacheLayout cache(options.out, scene.setup.name, manifest.framePadding);
  for (int frame = range.first; frame <= range.last; ++frame) {
    std::error_code missing;
    if (!std::filesystem::exists(cache.framePath(frame), missing))
      throw Error(cat(cache.framePath(frame).string(), ": the cache has no frame ", frame,
                      " (the run stopped at frame ", manifest.framesComplete,
                      "; continue it with run --resume)"));
  }

  // As `run` rendered: framed on the whole shot, unless it rendered while simulating.
  RenderOptions framed = render;
  if (scene.output.png && !run.renderWhileSimulating)
    framed.shotBounds = cache.shotBounds(manifest.framesWritten);

  Manifest exported = manifest;
  exported.sequences.clear();
  std::vector<std::unique_ptr<FrameSink>> sinks =
      openSinks(run, scene.setup.name, scene.output, topology, framed, vdb, checkpointEvery,
                /*keepExisting=*/true, exported);
  const char upAxis = run.upAxis ? (*run.upAxis)[0] : 'y';
  for (std::unique_ptr<FrameSink>& writer : openPointCacheWriters(
           scene.setup.name, scene.output, topology, options.out, upAxis, exported))
    sinks.push_back(std::move(writer));
  // Point caches take every frame, in order.
  const FrameRange fed = pointCaches ? FrameRange{1, manifest.framesWritten} : range;
  FramePipeline pipeline(std::move(sinks), topology->particleCount());
  ProgressDisplay progress(fed.last - fed.first + 1, options.quiet);
  writeFromCache(cache, fed.first, fed.last, {}, pipeline, progress);
  progress.finish();

  // The manifest lists the sequences export added, so tools that read it find them.
  for (const OutputSequence& sequence : exported.sequences)
    if (std::none_of(manifest.sequences.begin(), manifest.sequences.end(),
                     [&](const OutputSequence& s) { return s.format == sequence.format; }))
      manifest.sequences.push_back(sequence);
  if (pointCaches) {
    // Merge per body: an export of MDD keeps the PC2 files a run listed, and the other way round.
    if (manifest.pointCaches.size() != exported.pointCaches.size())
      manifest.pointCaches = exported.pointCaches;
    for (std::size_t b = 0; b < exported.pointCaches.size(); ++b) {
      if (!exported.pointCaches[b].pc2.empty())
        manifest.pointCaches[b].pc2 = exported.pointCaches[b].pc2;
      if (!exported.pointCaches[b].mdd.empty())
        manifest.pointCaches[b].mdd = exported.pointCaches[b].mdd;
      manifest.pointCaches[b].body = exported.pointCaches[b].body;
      manifest.pointCaches[b].restMesh = exported.pointCaches[b].restMesh;
    }
    manifest.pointCacheUp = exported.pointCacheUp;
  }
  writeManifest(options.out, manifest);
  std::printf("exported frames %d to %d (%s) from %s in %.2f s\n", range.first, range.last,
              formatBytes(pipeline.bytesWritten()).c_str(), cache.directory().string().c_str(),
              progress.elapsedSeconds());
  for (const OutputSequence& sequence : exported.sequences)
    std::printf("%s sequence: %s\n", sequence.format.c_str(),
                (options.out / sequence.pattern).string().c_str());
  return 0;
}

}  // namespace

int exportCommand(const ExportOptions& options) {
  return reportingErrors([&] { return exportFrames(options); });
}

}  // namespace softbake
