#pragma once
/// What `softbake run` is asked to do: its input and output folder, and the options of the option
/// table (importers/option_table.hpp) as given, from a command line, Python's keywords or a
/// run's record. Those that land in the scene or its loading stay in `given`; the run's own land
/// in the fields below.

#include <filesystem>
#include <optional>
#include <string>

#include "importers/option_table.hpp"
#include "importers/scene_file.hpp"

namespace softbake {

struct RunOptions {
  std::string input;  ///< scene .json, a mesh file, or empty for the built-in default scene
  std::filesystem::path out = "out";
  GivenOptions given = GivenOptions::object();  ///< every option of the table given, checked

  // Landed from `given` by landRunOptions().
  SceneLoadOptions load;
  bool renderWhileSimulating = false;  ///< render as it simulates, framed on the first frame
  std::optional<double> voxelSize;
  bool vdbFog = false;
  std::optional<std::string> upAxis;          ///< "y" or "z", for the VDB export
  std::optional<std::string> vdbCompression;  ///< "zip", "blosc" or "none"
  int threads = 0;                            ///< 0: all cores
  bool quiet = false;
  double maxOutputGib = 1024;  ///< refuse runs whose frames would take more, roughly
  bool cache = true;           ///< write the simulation cache to OUT/cache (--no-cache: off)
  /// Write the cache and nothing else; `export --all` writes the outputs later (a farm's split).
  bool cacheOnly = false;
  std::optional<int> checkpointEvery;  ///< frames between checkpoints; unset: ≤ 10% of the cache
  bool resume = false;                 ///< continue the run whose manifest is in `out`
  /// Write a bake report into this folder (bake/bake_report.hpp), and the frames' records it is
  /// made from into OUT/frame_stats.jsonl; also when the run fails or is interrupted.
  std::optional<std::filesystem::path> report;

  /// The command as typed, quoted for a shell: printed with --resume when a run is interrupted.
  std::string commandLine;
};

/// Sets the fields of `options` from `options.given`: the loading options and the run's own (the
/// scene's wait for the scene: applySceneOptions()). Throws softbake::Error for options that
/// exclude each other, std::logic_error for a run option of the table no field takes.
void landRunOptions(RunOptions& options);

}  // namespace softbake
