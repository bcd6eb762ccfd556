#pragma once
/// What `softbake run` and `softbake bench` accept as their INPUT: a scene .json, a mesh file in
/// any format assimp reads, a built-in scene name (default, balls1k, balls10k, balls100k,
/// balls1m), or nothing for the built-in default scene.

#include <optional>
#include <string>

#include "importers/scene_file.hpp"

namespace softbake {

/// A file of that name wins over a built-in scene of the same name. Throws softbake::Error naming
/// the input when it is neither.
SceneFile loadSceneInput(const std::string& input, const SceneLoadOptions& options = {});

/// Prints what loading found that may be wrong, one "warning: …" line each on stderr.
void printWarnings(const SceneFile& scene);

/// The simulation settings `run` and `bench` both take from the command line; unset ones keep the
/// scene's.
struct SimulationOverrides {
  std::optional<int> frames;
  std::optional<double> fps;
  std::optional<std::string> integrator;  ///< "explicit", "implicit"
  std::optional<std::string> substeps;    ///< "auto" or a count
  std::optional<std::string> broadPhase;  ///< "sbhash", "spatialhash", "bvh", "brute"
  std::optional<std::string> response;    ///< "two-sided", "paper", "none"
  std::optional<int> levels;              ///< sbhash subdivision level
  bool noResponse = false;                ///< detection only: --response none
  bool noPairCache = false;               ///< run the broad phase every substep
};

/// Writes the overrides that are set into `settings`. Throws softbake::Error naming the flag for
/// a broad phase or response it does not know.
void applySimulationOverrides(const SimulationOverrides& overrides, SimulationSettings& settings);

}  // namespace softbake
