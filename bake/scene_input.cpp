#include "bake/scene_input.hpp"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/bench_scenes.hpp"

namespace softbake {

namespace {

// Scene files and mesh files are bounded while they load, before their meshes are read.
SceneFile withinBodyLimit(SceneFile builtIn, const SceneLoadOptions& options) {
  const std::size_t bodies = builtIn.setup.bodies.size();
  if (bodies > options.maxBodies)
    throw Error(cat("scene '", builtIn.setup.name, "': ", bodies, " bodies, above the limit of ",
                    options.maxBodies, " (--max-bodies raises it)"));
  return builtIn;
}

}  // namespace

SceneFile loadSceneInput(const std::string& input, const SceneLoadOptions& options) {
  if (input.empty()) return withinBodyLimit(defaultScene(), options);
  const std::filesystem::path path(input);
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    if (std::optional<SceneFile> builtIn = benchScene(input))
      return withinBodyLimit(std::move(*builtIn), options);
    std::string names;
    for (const std::string& name : benchSceneNames()) names += (names.empty() ? "" : ", ") + name;
    throw Error(cat(input, ": no such file, and not a built-in scene (", names, ")"));
  }
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".json") return loadSceneFile(path, options);
  return sceneFromMeshFile(path, options);
}

void printWarnings(const SceneFile& scene) {
  std::fflush(stdout);  // after whatever the command printed before
  for (const std::string& warning : scene.warnings)
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
}

}  // namespace softbake
