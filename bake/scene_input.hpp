#pragma once
/// What `softbake run` and `softbake bench` accept as their INPUT: a scene .json, a mesh file in
/// any format assimp reads, a built-in scene name (default, balls1k, balls10k, balls100k,
/// balls1m), or nothing for the built-in default scene.

#include <string>

#include "importers/scene_file.hpp"

namespace softbake {

/// A file of that name wins over a built-in scene of the same name. Throws softbake::Error naming
/// the input when it is neither.
SceneFile loadSceneInput(const std::string& input, const SceneLoadOptions& options = {});

/// Prints what loading found that may be wrong, one "warning: …" line each on stderr.
void printWarnings(const SceneFile& scene);

}  // namespace softbake
