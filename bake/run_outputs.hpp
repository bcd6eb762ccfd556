#pragma once
/// The writers of a run, as `run` opens them and `export` opens them again from a run's record:
/// the render and VDB options from the scene and the command line, and one sink per output.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bake/interruption.hpp"
#include "bake/progress_display.hpp"
#include "bake/run_bake.hpp"
#include "core/simulator.hpp"
#include "exporters/vdb_sequence_writer.hpp"
#include "importers/scene_file.hpp"
#include "output/cache_writer.hpp"
#include "output/frame.hpp"
#include "output/frame_pipeline.hpp"
#include "output/manifest.hpp"
#include "render/frame_renderer.hpp"

namespace softbake {

/// The renderer's options: its defaults, with the scene's render settings (the options of the
/// table written over them: applySceneOptions()) over them.
RenderOptions renderOptions(const RenderSettings& scene);

/// The VDB export's options, validated against `topology` before anything is written.
VdbOptions vdbOptions(const RunOptions& options, const SceneTopology& topology);

/// Removes what a killed run was writing when it died: hidden temporary files of `scene` in
/// `folder`. Whole files stay, for a resumed run to keep.
void removeTemporaryFiles(const std::filesystem::path& folder, const std::string& scene);

/// Removes frames a previous run of the same scene left in `folder`, so the folder holds one
/// consistent sequence, and the temporary files of a run that was killed while writing.
void removeStaleFrames(const std::filesystem::path& folder, const std::string& scene,
                       const char* extension);

/// Every writer `output` asks for (the VDB writer when `vdb` is set too), the cache last (when
/// options.cache), each listed in
/// `manifest` in the same order: a sink's index is its bit in Frame::sinkMask. Unless
/// `keepExisting` (a resumed run, an export), the frames an earlier run of the scene left are
/// removed first.
std::vector<std::unique_ptr<FrameSink>> openSinks(
    const RunOptions& options, const std::string& name, const OutputOptions& output,
    const std::shared_ptr<const SceneTopology>& topology, const RenderOptions& render,
    const std::optional<VdbOptions>& vdb, int checkpointEvery, bool keepExisting,
    Manifest& manifest);

/// The PC2 and MDD writers `output` asks for, each body's rest mesh written now (OUT/cache_mesh),
/// their files listed in `manifest.pointCaches`. `upAxis` is the --up option ('y' or 'z').
std::vector<std::unique_ptr<FrameSink>> openPointCacheWriters(
    const std::string& name, const OutputOptions& output,
    const std::shared_ptr<const SceneTopology>& topology, const std::filesystem::path& out,
    char upAxis, Manifest& manifest);

/// Whether every file `manifest` lists for its point caches is in `out`.
bool pointCachesWritten(const std::filesystem::path& out, const Manifest& manifest);

/// The checkpoint interval that keeps `simulator`'s checkpoints within a tenth of its cache,
/// from the sizes of a checkpoint and a frame record of its state now.
int defaultCheckpointEvery(const Simulator& simulator);

/// Feeds frames `first`…`last` from `cache` to `pipeline`, each to the sinks its entry of
/// `sinksPerFrame` ([frame − 1]; empty: all) names, then finishes the pipeline; stops early, after
/// a whole frame, when `interruption` has a signal. Returns the last frame fed. Throws
/// softbake::Error naming a cache file that is missing or damaged, or a writer that failed.
int writeFromCache(const CacheLayout& cache, int first, int last,
                   const std::vector<std::uint64_t>& sinksPerFrame, FramePipeline& pipeline,
                   ProgressDisplay& progress, const InterruptionGuard* interruption = nullptr);

}  // namespace softbake
