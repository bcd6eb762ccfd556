#include "cli/run_command.hpp"

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <regex>
#include <system_error>

#include "cli/progress_display.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "exporters/frame_pipeline.hpp"
#include "exporters/manifest.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "importers/scene_file.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

SceneFile loadInput(const std::string& input) {
  if (input.empty()) return defaultScene();
  const fs::path path(input);
  std::error_code error;
  if (!fs::exists(path, error)) throw Error(cat(input, ": no such file"));
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".json") return loadSceneFile(path);
  return sceneFromMeshFile(path);
}

void applyOverrides(const RunOptions& options, SceneFile& scene) {
  SimulationSettings& settings = scene.setup.settings;
  if (options.frames) settings.frames = *options.frames;
  if (options.fps) settings.fps = *options.fps;
  if (options.substeps)
    settings.substeps = *options.substeps == "auto" ? 0 : std::stoi(*options.substeps);
  if (options.framePadding) scene.output.framePadding = *options.framePadding;
}

void describeSubsteps(const SubstepChoice& choice) {
  const double boundMs = choice.boundTimeStep * 1e3, stepMs = choice.timeStep * 1e3;
  if (!std::isfinite(choice.boundTimeStep)) {
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

int run(const RunOptions& options) {
  std::optional<tbb::global_control> threadLimit;
  if (options.threads > 0)
    threadLimit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(options.threads));

  SceneFile scene = loadInput(options.input);
  applyOverrides(options, scene);
  for (const std::string& note : scene.notes) std::printf("note: %s\n", note.c_str());

  BuildReport report;
  Simulator simulator(buildWorld(scene.setup, &report));
  for (const std::string& note : report.notes) std::printf("note: %s\n", note.c_str());
  const World& world = simulator.world();
  if (world.bodies.size() > 1)
    std::printf(
        "note: collisions between soft bodies are not in this version yet: bodies pass "
        "through each other\n");
  if (!world.staticMeshes.empty())
    std::printf("note: static mesh colliders are loaded but not collided with in this version\n");
  const std::string& name = scene.setup.name;
  std::size_t triangles = 0;
  for (const Body& body : world.bodies) triangles += body.triangleCount;
  std::printf(
      "scene '%s': %zu bodies, %zu particles, %zu triangles, %zu springs; %d frames at %g fps\n",
      name.c_str(), world.bodies.size(), world.particleCount(), triangles, world.springs.size(),
      world.settings.frames, world.settings.fps);
  describeSubsteps(simulator.substeps());

  // Everything above validated the input: only now is anything written.
  fs::create_directories(options.out);
  fs::remove(options.out / "manifest.json");
  const int frames = world.settings.frames;
  Manifest manifest = describeWorld(world, name, frames, scene.output.framePadding);
  std::vector<std::unique_ptr<FrameSink>> sinks;
  if (scene.output.obj) {
    removeStaleFrames(options.out / "obj", name, ".obj");
    auto obj =
        std::make_unique<ObjSequenceWriter>(world, options.out, name, scene.output.framePadding);
    manifest.sequences.push_back(obj->sequence());
    sinks.push_back(std::move(obj));
  }
  FramePipeline pipeline(std::move(sinks), world.particleCount());

  std::fflush(stdout);  // the scene summary comes before the progress lines on stderr
  ProgressDisplay progress(frames, options.quiet);
  for (int frame = 1; frame <= frames; ++frame) {
    if (frame > 1) simulator.advanceToFrame(frame);
    Frame& out = pipeline.acquire();
    out.number = frame;
    out.time = (frame - 1) / world.settings.fps;
    std::copy(world.position.begin(), world.position.end(), out.positions.begin());
    pipeline.submit(out);
    progress.update(frame);
  }
  pipeline.finish();
  progress.finish();
  const double seconds = progress.elapsedSeconds();

  writeManifest(options.out, manifest);

  const double steps = double(frames - 1) * simulator.substeps().substeps;
  std::printf("wrote %d frames (%s) to %s in %.2f s: %.0f steps, %.0f steps/s\n", frames,
              formatBytes(pipeline.bytesWritten()).c_str(), options.out.string().c_str(), seconds,
              steps, seconds > 0 ? steps / seconds : 0.0);
  for (const OutputSequence& sequence : manifest.sequences)
    std::printf("%s sequence: %s\n", sequence.format.c_str(),
                (options.out / sequence.pattern).string().c_str());
  std::printf("manifest: %s\n", (options.out / "manifest.json").string().c_str());
  return 0;
}

}  // namespace

int runCommand(const RunOptions& options) {
  try {
    return run(options);
  } catch (const Error& error) {
    std::fflush(stdout);
    std::fprintf(stderr, "\nsoftbake: error: %s\n", error.what());
  } catch (const std::filesystem::filesystem_error& error) {
    std::fflush(stdout);
    std::fprintf(stderr, "\nsoftbake: error: %s\n", error.what());
  } catch (const std::bad_alloc&) {
    std::fflush(stdout);
    std::fprintf(stderr, "\nsoftbake: error: out of memory; try a smaller scene\n");
  }
  return 1;
}

}  // namespace softbake
