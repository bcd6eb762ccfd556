#include "core/scene/material.hpp"

#include <array>

namespace softbake {

namespace {
constexpr Scalar kThickness = Material{}.thickness;
// Tuned on a 1 kg ball of radius 0.5 m: "stiff" barely dents on landing, "balloon" visibly
// inflates above its rest size, "jelly" wobbles for about a second.
constexpr std::array kPresets = {
    NamedMaterial{"stiff",
                  "hard rubber: small dents, fast recovery",
                  {5000, 2500, 0.10f, 300, kThickness, 80000}},
    NamedMaterial{"rubber",
                  "a rubber ball: springy, keeps its shape",
                  {1000, 300, 0.05f, 100, kThickness, 40000}},
    NamedMaterial{
        "jelly", "soft and wobbly, little gas pressure", {150, 40, 0.03f, 15, kThickness, 8000}},
    // A balloon's gas is what it is: it inflates and gives under load by design.
    NamedMaterial{"balloon",
                  "thin elastic skin held up by gas pressure",
                  {250, 5, 0.03f, 400, kThickness, 0}},
};
}  // namespace

std::span<const NamedMaterial> materialPresets() {
  return kPresets;
}

std::optional<Material> findMaterialPreset(std::string_view name) {
  for (const NamedMaterial& preset : kPresets)
    if (preset.name == name) return preset.material;
  return std::nullopt;
}

}  // namespace softbake
