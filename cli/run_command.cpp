#include "cli/run_command.hpp"

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <regex>
#include <system_error>

#include "cli/command_errors.hpp"
#include "cli/output_budget.hpp"
#include "cli/progress_display.hpp"
#include "cli/scene_input.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "exporters/contact_writer.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "exporters/vdb_sequence_writer.hpp"
#include "importers/scene_file.hpp"
#include "output/frame_pipeline.hpp"
#include "output/manifest.hpp"
#include "render/png_sequence_renderer.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

void applyOverrides(const RunOptions& options, SceneFile& scene) {
  applySimulationOverrides(options, scene.setup.settings);
  if (options.framePadding) scene.output.framePadding = *options.framePadding;
  if (options.contacts) scene.output.contacts = true;
  if (options.render) scene.output.png = *options.render;
  if (options.vdb) scene.output.vdb = true;
}

/// The scene's render settings, then the command line's.
RenderOptions renderOptions(const RunOptions& options, const RenderSettings& scene) {
  RenderOptions render;
  render.width = scene.width.value_or(render.width);
  render.height = scene.height.value_or(render.height);
  render.samples = scene.samples.value_or(render.samples);
  render.cameraPosition = scene.cameraPosition;
  render.cameraTarget = scene.cameraTarget;
  render.fovDegrees = scene.fovDegrees.value_or(render.fovDegrees);
  render.contacts = scene.contactSpheres.value_or(render.contacts) && !options.noContactSpheres;
  render.contactColor = scene.contactColor.value_or(render.contactColor);
  render.contactRadius = scene.contactRadius.value_or(render.contactRadius);
  render.wireframe = scene.wireframe.value_or(render.wireframe);
  for (const std::optional<Vec3f>& color : scene.bodyColors)
    render.bodyColors.push_back(color.value_or(Vec3f(-1, -1, -1)));
  if (options.size) {
    int width = 0, height = 0;
    char x = 0, extra = 0;
    if (std::sscanf(options.size->c_str(), "%d%c%d%c", &width, &x, &height, &extra) != 3 ||
        (x != 'x' && x != 'X') || width < 16 || height < 16 || width > 16384 || height > 16384)
      throw Error(cat("--size: expected WIDTHxHEIGHT between 16x16 and 16384x16384, got '",
                      *options.size, "'"));
    render.width = width;
    render.height = height;
  }
  return render;
}

VdbOptions vdbOptions(const RunOptions& options, const SceneTopology& topology) {
  VdbOptions vdb;
  if (options.voxelSize) vdb.voxelSize = *options.voxelSize;
  vdb.fog = options.vdbFog;
  if (options.upAxis) vdb.upAxis = (*options.upAxis)[0];
  if (options.vdbCompression)
    vdb.compression = *options.vdbCompression == "blosc"  ? VdbOptions::Compression::Blosc
                      : *options.vdbCompression == "none" ? VdbOptions::Compression::None
                                                          : VdbOptions::Compression::Zip;
  vdb.fps = topology.settings.fps;
  vdb.units = topology.settings.units;
  validate(vdb, topology);  // before anything is written
  return vdb;
}

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

/// Removes frames a previous, longer run of the same scene left in `folder`, so the folder holds
/// one consistent sequence.
void removeStaleFrames(const fs::path& folder, const std::string& scene, const char* extension) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return;
  const std::regex frameName(
      std::regex_replace(scene, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") + "_[0-9]+\\" +
      extension);
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error))
    if (std::regex_match(entry.path().filename().string(), frameName))
      fs::remove(entry.path(), error);
}

/// Surfaces that intersect at the start, per pair of bodies (or colliders) and per body with
/// itself, and what the run does with them.
void describeInitialOverlaps(const Simulator& simulator) {
  const InitialOverlaps& overlaps = simulator.initialOverlaps();
  if (overlaps.empty()) return;
  const SceneTopology& topology = simulator.topology();
  std::string list;
  for (const SurfaceOverlap& overlap : overlaps.bySurfaces) {
    list += list.empty() ? "" : ", ";
    list += overlap.firstSurface == overlap.secondSurface
                ? cat("'", topology.surfaceName(overlap.firstSurface), "' with itself")
                : cat("'", topology.surfaceName(overlap.firstSurface), "' and '",
                      topology.surfaceName(overlap.secondSurface), "'");
    list += cat(" (", overlap.trianglePairs, " triangle pairs)");
  }
  const bool ignore = topology.settings.collisions.initialOverlap == InitialOverlapMode::Ignore;
  std::printf("warning: surfaces intersect at the start: %s; %s\n", list.c_str(),
              ignore ? "those surfaces never collide with each other (initial_overlap \"ignore\")"
                     : "they are taken apart over the first frames, two bodies moved as wholes "
                       "without velocity (initial_overlap \"separate\"; \"ignore\" glues them)");
}

/// The scene's size, its substeps and its collision setup, on stdout.
void describeRun(const std::string& name, const Simulator& simulator) {
  const SceneTopology& topology = simulator.topology();
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
  describeInitialOverlaps(simulator);
}

/// Every writer the scene's output asks for, each sequence's stale frames of an earlier, longer
/// run removed and the sequence listed in `manifest`.
std::vector<std::unique_ptr<FrameSink>> openSinks(const RunOptions& options, const SceneFile& scene,
                                                  const Simulator& simulator,
                                                  const RenderOptions& render,
                                                  const std::optional<VdbOptions>& vdb,
                                                  Manifest& manifest) {
  const std::shared_ptr<const SceneTopology>& topology = simulator.sharedTopology();
  const std::string& name = scene.setup.name;
  const int padding = scene.output.framePadding;
  std::vector<std::unique_ptr<FrameSink>> sinks;
  auto addSequence = [&](const char* folder, const char* extension, auto sink) {
    removeStaleFrames(options.out / folder, name, extension);
    manifest.sequences.push_back(sink->sequence());
    sinks.push_back(std::move(sink));
  };
  if (scene.output.obj)
    addSequence("obj", ".obj",
                std::make_unique<ObjSequenceWriter>(topology, options.out, name, padding));
  if (scene.output.contacts)
    addSequence("contacts", ".json",
                std::make_unique<ContactWriter>(*topology, options.out, name, padding));
  if (vdb)
    addSequence("vdb", ".vdb",
                std::make_unique<VdbSequenceWriter>(*topology, options.out, name, *vdb, padding));
  if (scene.output.png)
    addSequence(
        "png", ".png",
        std::make_unique<PngSequenceRenderer>(topology, options.out, name, render, padding));
  return sinks;
}

/// Simulates every frame and hands it to the writers; returns the contacts over all substeps.
StepStats bake(Simulator& simulator, FramePipeline& pipeline, ProgressDisplay& progress) {
  const SimulationState& state = simulator.state();
  const SimulationSettings& settings = simulator.topology().settings;
  StepStats totals;
  for (int frame = 1; frame <= settings.frames; ++frame) {
    if (frame > 1) {
      simulator.advanceToFrame(frame);
      const StepStats& stats = simulator.lastFrameStats();
      totals.contacts += stats.contacts;
      totals.planeContacts += stats.planeContacts;
      totals.responses.particleResponses += stats.responses.particleResponses;
      totals.responses.cornerResponses += stats.responses.cornerResponses;
      totals.responses.edgePushes += stats.responses.edgePushes;
    }
    Frame& out = pipeline.acquire();
    out.number = frame;
    out.time = (frame - 1) / settings.fps;
    std::copy(state.position.begin(), state.position.end(), out.positions.begin());
    std::copy(state.velocity.begin(), state.velocity.end(), out.velocities.begin());
    out.contacts = simulator.contacts();
    pipeline.submit(out);
    progress.update(frame);
  }
  return totals;
}

int run(const RunOptions& options) {
  std::optional<tbb::global_control> threadLimit;
  if (options.threads > 0)
    threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(options.threads));

  SceneFile scene = loadSceneInput(options.input, options.load);
  applyOverrides(options, scene);
  for (const std::string& note : scene.notes) std::printf("note: %s\n", note.c_str());
  printWarnings(scene);
  const RenderOptions render = renderOptions(options, scene.render);
  requireOutputWithin(scene, render.width, render.height, options.maxOutputGib * 0x1p30);

  BuildReport report;
  Simulator simulator(buildSceneTopology(scene.setup, &report));
  for (const std::string& note : report.notes) std::printf("note: %s\n", note.c_str());
  const SceneTopology& topology = simulator.topology();
  const std::string& name = scene.setup.name;
  describeRun(name, simulator);
  std::optional<VdbOptions> vdb;
  if (scene.output.vdb) vdb = vdbOptions(options, topology);

  // Everything above validated the input: only now is anything written.
  fs::create_directories(options.out);
  fs::remove(options.out / "manifest.json");
  const int frames = topology.settings.frames;
  Manifest manifest = describeScene(topology, name, frames, scene.output.framePadding);
  FramePipeline pipeline(openSinks(options, scene, simulator, render, vdb, manifest),
                         topology.particleCount());

  std::fflush(stdout);  // the scene summary comes before the progress lines on stderr
  ProgressDisplay progress(frames, options.quiet);
  const StepStats totals = bake(simulator, pipeline, progress);
  pipeline.finish();
  progress.finish();
  const double seconds = progress.elapsedSeconds();

  writeManifest(options.out, manifest);

  const double steps = double(simulator.stepsTaken());
  std::printf("wrote %d frames (%s) to %s in %.2f s: %.1f frames/s, %.0f steps, %.0f steps/s\n",
              frames, formatBytes(pipeline.bytesWritten()).c_str(), options.out.string().c_str(),
              seconds, seconds > 0 ? frames / seconds : 0.0, steps,
              seconds > 0 ? steps / seconds : 0.0);
  if (simulator.collides())
    std::printf(
        "contacts over all substeps: %zu (particle %zu, corner %zu, edge pushes %zu); "
        "plane contacts %zu\n",
        totals.contacts, totals.responses.particleResponses, totals.responses.cornerResponses,
        totals.responses.edgePushes, totals.planeContacts);
  for (const OutputSequence& sequence : manifest.sequences)
    std::printf("%s sequence: %s\n", sequence.format.c_str(),
                (options.out / sequence.pattern).string().c_str());
  std::printf("manifest: %s\n", (options.out / "manifest.json").string().c_str());
  return 0;
}

}  // namespace

int runCommand(const RunOptions& options) {
  return reportingErrors([&] { return run(options); });
}

}  // namespace softbake
