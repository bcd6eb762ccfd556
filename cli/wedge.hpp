#pragma once
/// Wedges: one scene, some of its keys varied, every combination a variant scene of its own.
///
///   softbake wedge SCENE --vary bodies[0].material=rubber,jelly --vary settings.fps=24,48 --out
///   DIR
///
/// writes DIR/wedge_000/scene.json … DIR/wedge_003/scene.json (the cartesian product, the first
/// --vary slowest), DIR/wedge.csv and DIR/wedge.md (which variant sets what), then bakes each
/// variant into its own folder, several at once. `softbake farm slurm` expands wedges the same way.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bake/run_bake.hpp"

namespace softbake {

/// One --vary: a key path into the scene JSON ("bodies[1].material.stiffness") and its values.
struct WedgeVariation {
  std::string path;
  std::vector<nlohmann::json> values;
};

/// Reads "PATH=V1,V2,…". Each value is JSON (1000, true, [0,-1,0], "rubber") or, when it does not
/// parse as JSON, a string (rubber); commas inside brackets or quotes belong to the value. Throws
/// softbake::Error quoting the text.
WedgeVariation parseVariation(const std::string& text);

/// A variant: its folder name and its scene.
struct WedgeVariant {
  std::string name;  ///< "wedge_000"
  nlohmann::json scene;
  std::vector<nlohmann::json> values;  ///< per variation, the value this variant has
};

/// The cartesian product of `variations` over `scene`, the first variation varying slowest. Mesh
/// paths are made absolute against `sceneDirectory`, so a variant scene loads from anywhere.
/// Throws softbake::Error naming the --vary whose path the scene does not have.
std::vector<WedgeVariant> expandWedge(const nlohmann::json& scene,
                                      const std::filesystem::path& sceneDirectory,
                                      const std::vector<WedgeVariation>& variations);

/// A variant as it lies on disk: the folder its run writes to and its scene file.
struct PreparedVariant {
  std::string name;
  std::filesystem::path folder;
  std::filesystem::path scene;
};

/// Expands the wedge of `input` (a scene .json or a built-in name) into `out`: every variant's
/// scene.json, checked by loading it, and the tables wedge.csv and wedge.md.
std::vector<PreparedVariant> prepareWedge(const std::string& input,
                                          const std::vector<WedgeVariation>& variations,
                                          const std::filesystem::path& out);

struct WedgeOptions {
  std::string input;
  std::vector<std::string> vary;  ///< "PATH=V1,V2,…"
  std::filesystem::path out = "wedge";
  int parallel = 0;                       ///< variants baked at once; 0: one per core
  bool bake = true;                       ///< false: write the variants and tables only
  std::vector<std::string> runArguments;  ///< passed to every `softbake run`
};

/// Returns the process exit code: 0 when every variant baked, 1 otherwise (each failure named
/// with its log). Errors are printed, never thrown.
int wedgeCommand(const WedgeOptions& options);

}  // namespace softbake
