#pragma once
/// `softbake bench`: runs a scene with no output files and reports, per stage of the substep, the
/// median and 95th-percentile time per step, the contacts and broad-phase pairs per step and the
/// peak memory, ending each broad phase with one machine-readable line:
///
///   scene=fig7_10k_faces faces=10240 broadphase=bvh threads=2 steps=2000 steps_per_s=1620.3 …
///
/// Several broad phases run one after the other in the same process from the same initial state
/// (the paper's figures 7–8 put them side by side). `--csv` writes one row per step and broad
/// phase. `--with-exports` also writes every frame through the OBJ and VDB writers and the PNG
/// renderer, one at a time on the bench's thread, and reports each one's time per frame; the
/// simulation figures never include them.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bake/scene_input.hpp"
#include "importers/option_table.hpp"

namespace softbake {

struct BenchOptions {
  std::string input;  ///< scene .json, mesh file or built-in scene name
  /// The option table's, as run takes them, but for "broadphase": an array of broad phases to
  /// run one after the other.
  GivenOptions given = GivenOptions::object();
  SceneLoadOptions load;      ///< landed from `given`
  std::optional<long> steps;  ///< exact substep count instead of whole frames
  long warmupSteps = 0;       ///< steps simulated before measuring, not reported
  int threads = 0;            ///< 0: all cores
  std::optional<std::filesystem::path> csv;
  bool withExports = false;
  std::filesystem::path out;  ///< where exports go; empty: a temporary folder
};

/// Returns the process exit code. Errors are printed, never thrown.
int benchCommand(const BenchOptions& options);

}  // namespace softbake
