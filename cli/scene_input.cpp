#include "cli/scene_input.hpp"

#include <cctype>
#include <filesystem>
#include <system_error>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/bench_scenes.hpp"

namespace softbake {

SceneFile loadSceneInput(const std::string& input) {
  if (input.empty()) return defaultScene();
  const std::filesystem::path path(input);
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    if (std::optional<SceneFile> builtIn = benchScene(input)) return std::move(*builtIn);
    std::string names;
    for (const std::string& name : benchSceneNames()) names += (names.empty() ? "" : ", ") + name;
    throw Error(cat(input, ": no such file, and not a built-in scene (", names, ")"));
  }
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".json") return loadSceneFile(path);
  return sceneFromMeshFile(path);
}

}  // namespace softbake
