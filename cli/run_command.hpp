#pragma once
/// `softbake run`: load a scene (or a mesh, or the built-in default), simulate it, and write the
/// frame sequences while the simulation goes on.

#include <filesystem>
#include <optional>
#include <string>

#include "cli/scene_input.hpp"

namespace softbake {

struct RunOptions : SimulationOverrides {
  std::string input;  ///< scene .json, a mesh file, or empty for the built-in default scene
  SceneLoadOptions load;
  std::filesystem::path out = "out";
  std::optional<int> framePadding;
  bool contacts = false;                    ///< write OUT/contacts/<scene>_0001.json …
  std::optional<bool> render;               ///< --render / --no-render; unset: the scene's choice
  std::optional<std::string> size;          ///< "1280x720"
  bool noContactSpheres = false;            ///< render without the contact spheres
  std::optional<std::string> contactsView;  ///< "xray" or "opaque"; unset: the scene's, else auto
  bool vdb = false;                         ///< write OUT/vdb/<scene>_0001.vdb …
  bool pc2 = false;  ///< write OUT/pc2/<scene>_<body>.pc2 and the rest meshes
  bool mdd = false;  ///< write OUT/mdd/<scene>_<body>.mdd and the rest meshes
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
  /// Render each PNG frame as it is simulated, the camera framed on the first frame, instead of
  /// from the cache once the shot is simulated, framed on all of it.
  bool renderWhileSimulating = false;
  /// Write a bake report into this folder (cli/bake_report.hpp), and the frames' records it is
  /// made from into OUT/frame_stats.jsonl; also when the run fails or is interrupted.
  std::optional<std::filesystem::path> report;
  /// The command as typed, quoted for a shell: printed with --resume when a run is interrupted.
  std::string commandLine;
};

/// Runs the job; returns the process exit code. Errors are printed, never thrown.
int runCommand(const RunOptions& options);

}  // namespace softbake
