#include "importers/bench_scenes.hpp"

#include <cmath>

#include "importers/json_reader.hpp"

namespace softbake {

namespace {

struct BallsScene {
  const char* name;
  int balls, subdivisions;
};

constexpr BallsScene kBallsScenes[] = {
    {"balls1k", 4, 2}, {"balls10k", 8, 3}, {"balls100k", 20, 4}, {"balls1m", 48, 5}};

}  // namespace

std::vector<std::string> benchSceneNames() {
  std::vector<std::string> names{"default"};
  for (const BallsScene& scene : kBallsScenes) names.emplace_back(scene.name);
  return names;
}

nlohmann::json ballsSceneJson(std::string_view name, int balls, int subdivisions) {
  static const char* const kMaterials[] = {"rubber", "jelly", "balloon", "stiff"};
  const int perLayer = (balls + 1) / 2;
  const int columns = int(std::ceil(std::sqrt(double(perLayer))));
  nlohmann::json bodies = nlohmann::json::array();
  for (int i = 0; i < balls; ++i) {
    const int layer = i / perLayer, slot = i % perLayer;
    const int column = slot % columns, row = slot / columns;
    // Centred grid, 0.802 m apart (2 mm gaps); the upper layer sits in the hollows of the lower
    // one, 2 mm off too. Every ball moves towards a neighbour, so contacts start within a few
    // dozen steps at any resolution, and the scenes measure contact, not free fall.
    constexpr double kSpacing = 0.802, kHalf = kSpacing / 2;
    const double x = (column - (columns - 1) / 2.0) * kSpacing + kHalf * layer;
    const double z = (row - (columns - 1) / 2.0) * kSpacing + kHalf * layer;
    const double y = 0.45 + std::sqrt(kSpacing * kSpacing - 2 * kHalf * kHalf) * layer;
    const double vx = layer == 0 ? (column % 2 == 0 ? 0.5 : -0.5) : 0.0;
    const double vz = layer == 0 ? (row % 2 == 0 ? 0.5 : -0.5) : 0.0;
    const double vy = layer == 0 ? 0.0 : -1.0;
    bodies.push_back(
        {{"name", "ball" + std::to_string(i)},
         {"mesh", {{"primitive", "icosphere"}, {"subdivisions", subdivisions}, {"radius", 0.4}}},
         {"transform", {{"translate", {x, y, z}}}},
         {"material", kMaterials[i % 4]},
         {"velocity", {vx, vy, vz}}});
  }
  return {{"name", std::string(name)},
          {"settings", {{"fps", 24}, {"frames", 48}, {"substeps", "auto"}}},
          {"bodies", bodies},
          {"colliders", {{{"type", "plane"}, {"name", "ground"}}}}};
}

std::optional<nlohmann::json> benchSceneJson(std::string_view name) {
  if (name == "default") return parseJsonText(defaultSceneJson(), "built-in default scene");
  for (const BallsScene& scene : kBallsScenes)
    if (name == scene.name) return ballsSceneJson(scene.name, scene.balls, scene.subdivisions);
  return std::nullopt;
}

std::optional<SceneFile> benchScene(std::string_view name) {
  if (name == "default") return defaultScene();
  if (std::optional<nlohmann::json> json = benchSceneJson(name))
    return parseScene(*json, std::string(name), ".");
  return std::nullopt;
}

}  // namespace softbake
