#pragma once
/// Built-in scenes for `softbake bench`, by name, so a benchmark needs no files:
///
///   default     the built-in default scene (two balls thrown at each other)
///   balls1k     4 icosphere balls of 320 faces      (1,280 faces)
///   balls10k    8 balls of 1,280 faces               (10,240 faces; the figure 7–8 scene's size)
///   balls100k   20 balls of 5,120 faces              (102,400 faces)
///   balls1m     48 balls of 20,480 faces             (983,040 faces)
///
/// The balls* scenes are one family for the scaling runs: 0.4 m balls in two staggered layers 2 mm
/// apart, the lower layer moving towards each other and the upper one falling into it, over a
/// ground plane, with the figure 7 scene's mix of rubber, jelly, balloon and stiff materials.
/// More faces means more and finer balls, so collisions per face stay about the same.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "importers/scene_file.hpp"

namespace softbake {

/// The names above.
std::vector<std::string> benchSceneNames();

/// The scene of a built-in name, or nothing when `name` is not one.
std::optional<SceneFile> benchScene(std::string_view name);

/// The JSON a built-in scene is built from (`softbake scene NAME` prints it), or nothing when
/// `name` is not one.
std::optional<nlohmann::json> benchSceneJson(std::string_view name);

/// The JSON of a balls scene of `balls` icosphere balls subdivided `subdivisions` times.
nlohmann::json ballsSceneJson(std::string_view name, int balls, int subdivisions);

}  // namespace softbake
