#pragma once
/// `softbake scene NAME_OR_FILE`: prints a scene's JSON on stdout, so other tools (the Blender
/// peer benchmark, bench/blender_peer.sh) can rebuild exactly the scene softbake simulates. A
/// built-in name (default, balls1k, balls10k, balls100k, balls1m) prints the JSON the scene is
/// built from; a .json file prints its JSON as parsed (comments dropped), after checking that it
/// loads. Mesh files have no scene JSON and are refused.

#include <string>

#include <nlohmann/json.hpp>

namespace CLI {
class App;
}

namespace softbake {

struct SceneCommandOptions {
  std::string input;  ///< built-in scene name or scene .json file
};

/// The JSON of `input`, a scene .json file (checked by loading it) or a built-in scene name; a
/// file of that name wins, as for `run`. Throws softbake::Error naming the input.
nlohmann::json resolveSceneJson(const std::string& input);

/// Adds the `scene` subcommand to `app`, filling `options` when it is parsed.
CLI::App* addSceneCommand(CLI::App& app, SceneCommandOptions& options);

/// Returns the process exit code. Errors are printed, never thrown.
int sceneCommand(const SceneCommandOptions& options);

}  // namespace softbake
