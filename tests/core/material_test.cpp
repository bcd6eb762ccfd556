// The material presets hold the values the Materials table documents (docs/materials.md): the table
// is read from that page itself, so the code and the documentation cannot drift apart unnoticed.
#include "core/scene/material.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <vector>

namespace softbake {
namespace {

struct DocumentedPreset {
  std::string name, character;
  double stiffness = 0, bendStiffness = 0, damping = 0, pressure = 0, bulkModulus = 0;
};

std::string trimmed(const std::string& text) {
  const std::size_t first = text.find_first_not_of(' ');
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(' ') - first + 1);
}

/// The rows of the table under "# Materials" in docs/materials.md, up to the next heading:
/// | `rubber` (default) | 1000 | 300 | 0.05 | 100 | 40000 | a rubber ball: ... |
std::vector<DocumentedPreset> documentedPresets() {
  std::ifstream page(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "docs" / "materials.md");
  std::vector<DocumentedPreset> presets;
  bool inSection = false;
  for (std::string line; std::getline(page, line);) {
    if (line.rfind("#", 0) == 0) inSection = line == "# Materials";
    if (!inSection || line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::istringstream row(line.substr(1));
    for (std::string cell; std::getline(row, cell, '|');) cells.push_back(trimmed(cell));
    if (cells.size() < 7) continue;
    DocumentedPreset preset;
    preset.name = cells[0].substr(1, cells[0].find('`', 1) - 1);
    preset.stiffness = std::stod(cells[1]);
    preset.bendStiffness = std::stod(cells[2]);
    preset.damping = std::stod(cells[3]);
    preset.pressure = std::stod(cells[4]);
    preset.bulkModulus = std::stod(cells[5]);
    preset.character = cells[6];
    presets.push_back(preset);
  }
  return presets;
}

TEST(MaterialPresets, HoldTheDocumentedValuesInTheirOrder) {
  const std::vector<DocumentedPreset> documented = documentedPresets();
  const std::span<const NamedMaterial> presets = materialPresets();
  ASSERT_EQ(documented.size(), 4u) << "the Materials table of docs/materials.md was not found";
  ASSERT_EQ(presets.size(), documented.size());
  for (std::size_t i = 0; i < presets.size(); ++i) {
    const DocumentedPreset& doc = documented[i];
    const NamedMaterial& preset = presets[i];
    SCOPED_TRACE(doc.name);
    EXPECT_EQ(preset.name, doc.name);
    EXPECT_EQ(preset.description, doc.character);
    // The table gives each value to the digit; the presets hold floats.
    EXPECT_FLOAT_EQ(float(preset.material.stiffness), float(doc.stiffness));
    EXPECT_FLOAT_EQ(float(preset.material.bendStiffness), float(doc.bendStiffness));
    EXPECT_FLOAT_EQ(float(preset.material.damping), float(doc.damping));
    EXPECT_FLOAT_EQ(float(preset.material.pressure), float(doc.pressure));
    EXPECT_FLOAT_EQ(float(preset.material.bulkModulus), float(doc.bulkModulus));
    const std::optional<Material> found = findMaterialPreset(doc.name);
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(found->stiffness, preset.material.stiffness);
  }
}

TEST(MaterialPresets, TheDefaultMaterialIsRubber) {
  // The table marks `rubber` "(default)": a body with no material gets it.
  const Material fallback;
  const Material rubber = *findMaterialPreset("rubber");
  EXPECT_EQ(fallback.stiffness, rubber.stiffness);
  EXPECT_EQ(fallback.bendStiffness, rubber.bendStiffness);
  EXPECT_EQ(fallback.damping, rubber.damping);
  EXPECT_EQ(fallback.pressure, rubber.pressure);
  EXPECT_EQ(fallback.bulkModulus, rubber.bulkModulus);
  EXPECT_FALSE(findMaterialPreset("Rubber").has_value());
  EXPECT_FALSE(findMaterialPreset("steel").has_value());
}

}  // namespace
}  // namespace softbake
