#include "bake/run_outputs.hpp"

#include <cstdio>
#include <regex>
#include <system_error>

#include "core/error.hpp"
#include "core/text.hpp"
#include "exporters/contact_writer.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "exporters/point_cache_writer.hpp"
#include "exporters/vdb_sequence_writer.hpp"
#include "render/png_sequence_renderer.hpp"

namespace softbake {

namespace fs = std::filesystem;

RenderOptions renderOptions(const RenderSettings& scene) {
  RenderOptions render;
  render.width = scene.width.value_or(render.width);
  render.height = scene.height.value_or(render.height);
  render.samples = scene.samples.value_or(render.samples);
  render.cameraPosition = scene.cameraPosition;
  render.cameraTarget = scene.cameraTarget;
  render.fovDegrees = scene.fovDegrees.value_or(render.fovDegrees);
  render.contacts = scene.contactSpheres.value_or(render.contacts);
  render.contactColor = scene.contactColor.value_or(render.contactColor);
  render.contactColorsByKind = scene.contactColorsByKind;
  if (scene.contactsView) render.contactsView = parseContactsView(*scene.contactsView);
  render.contactRadius = scene.contactRadius.value_or(render.contactRadius);
  render.wireframe = scene.wireframe.value_or(render.wireframe);
  for (const std::optional<Vec3f>& color : scene.bodyColors)
    render.bodyColors.push_back(color.value_or(Vec3f(-1, -1, -1)));
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

void removeTemporaryFiles(const fs::path& folder, const std::string& scene) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("." + scene, 0) == 0 && name.find(".tmp-") != std::string::npos)
      fs::remove(entry.path(), error);
  }
}

void removeStaleFrames(const fs::path& folder, const std::string& scene, const char* extension) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return;
  const std::regex frameName(
      std::regex_replace(scene, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") + "_[0-9]+\\" +
      extension);
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error))
    if (std::regex_match(entry.path().filename().string(), frameName))
      fs::remove(entry.path(), error);
  removeTemporaryFiles(folder, scene);
}

std::vector<std::unique_ptr<FrameSink>> openSinks(
    const RunOptions& options, const std::string& name, const OutputOptions& output,
    const std::shared_ptr<const SceneTopology>& topology, const RenderOptions& render,
    const std::optional<VdbOptions>& vdb, int checkpointEvery, bool keepExisting,
    Manifest& manifest) {
  const int padding = output.framePadding;
  std::vector<std::unique_ptr<FrameSink>> sinks;
  auto addSequence = [&](const char* folder, const char* extension, auto sink) {
    if (!keepExisting) removeStaleFrames(options.out / folder, name, extension);
    manifest.sequences.push_back(sink->sequence());
    sinks.push_back(std::move(sink));
  };
  if (output.obj)
    addSequence("obj", ".obj",
                std::make_unique<ObjSequenceWriter>(topology, options.out, name, padding,
                                                    render.bodyColors));
  if (output.contacts)
    addSequence("contacts", ".json",
                std::make_unique<ContactWriter>(*topology, options.out, name, padding));
  if (output.vdb && vdb)
    addSequence("vdb", ".vdb",
                std::make_unique<VdbSequenceWriter>(*topology, options.out, name, *vdb, padding));
  if (output.png)
    addSequence(
        "png", ".png",
        std::make_unique<PngSequenceRenderer>(topology, options.out, name, render, padding));
  if (!keepExisting) {
    // Checkpoints of an earlier run must never be taken for this one's.
    removeStaleFrames(options.out / "cache", name, ".sbframe");
    removeStaleFrames(options.out / "cache", name, ".sbcheckpoint");
  }
  if (options.cache)
    addSequence("cache", ".sbframe",
                std::make_unique<CacheWriter>(options.out, name, padding, topology->settings.frames,
                                              checkpointEvery, topology->particleCount()));
  return sinks;
}

std::vector<std::unique_ptr<FrameSink>> openPointCacheWriters(
    const std::string& name, const OutputOptions& output,
    const std::shared_ptr<const SceneTopology>& topology, const fs::path& out, char upAxis,
    Manifest& manifest) {
  std::vector<std::unique_ptr<FrameSink>> sinks;
  manifest.pointCaches.clear();
  if (!output.pc2 && !output.mdd) return sinks;
  writeRestMeshes(*topology, out, name, upAxis);
  manifest.pointCacheUp = std::string(1, upAxis);
  for (const PointCacheFormat format : {PointCacheFormat::Pc2, PointCacheFormat::Mdd}) {
    if (!(format == PointCacheFormat::Pc2 ? output.pc2 : output.mdd)) continue;
    auto writer = std::make_unique<PointCacheWriter>(
        topology, out, name, format, topology->settings.frames, topology->settings.fps, upAxis);
    const std::vector<PointCacheFiles> files = writer->files();
    manifest.pointCaches.resize(files.size());
    for (std::size_t b = 0; b < files.size(); ++b) {
      ManifestPointCache& entry = manifest.pointCaches[b];
      entry.body = files[b].body;
      entry.restMesh = files[b].restMesh;
      (format == PointCacheFormat::Pc2 ? entry.pc2 : entry.mdd) = files[b].cache;
    }
    sinks.push_back(std::move(writer));
  }
  return sinks;
}

bool pointCachesWritten(const fs::path& out, const Manifest& manifest) {
  std::error_code error;
  for (const ManifestPointCache& entry : manifest.pointCaches)
    for (const std::string* file : {&entry.restMesh, &entry.pc2, &entry.mdd})
      if (!file->empty() && !fs::exists(out / *file, error)) return false;
  return true;
}

int defaultCheckpointEvery(const Simulator& simulator) {
  Frame initial;
  initial.positions = simulator.state().position;
  initial.velocities = simulator.state().velocity;
  return defaultCheckpointInterval(encodeCheckpoint(simulator.checkpoint(), 1, 0).size(),
                                   encodeCacheFrame(initial).size());
}

int writeFromCache(const CacheLayout& cache, int first, int last,
                   const std::vector<std::uint64_t>& sinksPerFrame, FramePipeline& pipeline,
                   ProgressDisplay& progress, const InterruptionGuard* interruption) {
  for (int frame = first; frame <= last; ++frame) {
    if (interruption && interruption->signal() != 0) {
      pipeline.finish();
      return frame - 1;
    }
    const std::uint64_t sinks =
        sinksPerFrame.empty() ? ~std::uint64_t(0) : sinksPerFrame[std::size_t(frame - 1)];
    if (sinks != 0) {
      Frame& out = pipeline.acquire();
      cache.readFrame(frame, out);
      out.sinkMask = sinks;
      out.hasCheckpoint = false;
      pipeline.submit(out);
    }
    progress.update(frame - first + 1);
  }
  pipeline.finish();
  return last;
}

}  // namespace softbake
