#include "cli/scene_command.hpp"

#include <CLI/CLI.hpp>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <system_error>

#include "bake/command_errors.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/bench_scenes.hpp"
#include "importers/json_reader.hpp"
#include "importers/scene_file.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

/// A scene file's JSON, checked by loading it the way `run` would, so a broken scene is reported
/// here, naming the key, instead of in whatever tool reads the printed JSON.
nlohmann::json sceneFileJson(const fs::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".json")
    throw Error(cat(path.string(), ": a mesh file has no scene JSON; give a scene .json file or ",
                    "a built-in scene name"));
  nlohmann::json json = readJsonFile(path);
  parseScene(json, path.string(), path.parent_path());
  return json;
}

}  // namespace

nlohmann::json resolveSceneJson(const std::string& input) {
  std::error_code error;
  if (fs::exists(input, error)) return sceneFileJson(input);
  if (std::optional<nlohmann::json> builtIn = benchSceneJson(input)) return std::move(*builtIn);
  std::string names;
  for (const std::string& name : benchSceneNames()) names += (names.empty() ? "" : ", ") + name;
  throw Error(cat(input, ": no such file, and not a built-in scene (", names, ")"));
}

CLI::App* addSceneCommand(CLI::App& app, SceneCommandOptions& options) {
  CLI::App* sceneApp = app.add_subcommand(
      "scene",
      "Print a scene's JSON on stdout: a built-in scene (default, balls1k, balls10k, balls100k, "
      "balls1m) as the JSON it is built from, or a scene .json file as parsed.");
  sceneApp->add_option("scene", options.input, "built-in scene name or scene .json file")
      ->required();
  return sceneApp;
}

int sceneCommand(const SceneCommandOptions& options) {
  return reportingErrors([&] {
    const std::string text = resolveSceneJson(options.input).dump(2) + "\n";
    std::fwrite(text.data(), 1, text.size(), stdout);
    return std::fflush(stdout) == 0 ? 0 : 1;
  });
}

}  // namespace softbake
