#include <nlohmann/json.hpp>

#include "importers/json_reader.hpp"
#include "importers/scene_file.hpp"

namespace softbake {

namespace {

// examples/default.json holds the same text; a test keeps the two equal.
constexpr std::string_view kDefaultScene = R"json({
  "name": "default",
  "settings": {
    "fps": 24,
    "frames": 240,
    "substeps": "auto",
    "gravity": [0, -9.81, 0],
    "units": "m"
  },
  "bodies": [
    {
      "name": "ballA",
      "mesh": {"primitive": "icosphere", "subdivisions": 3, "radius": 0.5},
      "transform": {"translate": [-1.2, 1.5, 0]},
      "material": "rubber",
      "mass": 1.0,
      "velocity": [2.5, 2.0, 0]
    },
    {
      "name": "ballB",
      "mesh": {"primitive": "icosphere", "subdivisions": 3, "radius": 0.5},
      "transform": {"translate": [1.2, 1.8, 0]},
      "material": "rubber",
      "mass": 1.0,
      "velocity": [-2.5, 1.5, 0]
    }
  ],
  "colliders": [
    {"type": "plane", "name": "ground", "point": [0, 0, 0], "normal": [0, 1, 0],
     "restitution": 0.2, "friction": 0.3}
  ],
  "output": {"frame_padding": 4, "obj": true, "png": true}
}
)json";

constexpr std::string_view kDefaultSceneSource = "built-in default scene";

}  // namespace

std::string_view defaultSceneJson() {
  return kDefaultScene;
}

SceneFile defaultScene() {
  return parseScene(parseJsonText(kDefaultScene, kDefaultSceneSource), kDefaultSceneSource, {});
}

}  // namespace softbake
