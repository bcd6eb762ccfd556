#include "importers/import_losses.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

struct LossPattern {
  std::string_view words;  // lower case, matched anywhere in the message
  std::string_view lost;
};

// From assimp 5.2.5's loaders: the messages they log and then carry on with less geometry. Those
// that lose an attribute only (normals, UVs, an animation) are not here: the body is unchanged.
constexpr std::array kLossPatterns = {
    // glTF 2: an index past the vertex count drops the whole face.
    LossPattern{"those faces were dropped", "faces dropped"},
    // glTF 1 and 2: a vertex count that is not a multiple of 3 loses the last, partial triangle.
    LossPattern{"some vertices were dropped", "vertices dropped"},
    LossPattern{"invalid number of faces detected", "faces dropped"},
    // OFF: fewer rows than the header says, an empty face skipped, an index clamped to the last
    // vertex (which makes a different face).
    LossPattern{"the number of faces in the header is incorrect", "faces missing"},
    LossPattern{"the number of verts in the header is incorrect", "vertices missing"},
    LossPattern{"faces with zero indices aren't allowed", "faces dropped"},
    LossPattern{"vertex index is out of range", "faces changed (out-of-range index)"},
    // 3DS: an index past the vertex count.
    LossPattern{"vertex index overflow", "faces changed (out-of-range index)"},
    // STL: facets cut short or with extra corners.
    LossPattern{"a new facet begins but the old is not yet complete", "facets cut short"},
    LossPattern{"a facet with more than 3 vertices", "facets changed"},
    // COLLADA: a <p> list of the wrong length, a mesh the scene names but the file lacks.
    LossPattern{"expected different index count in <p> element", "faces changed"},
    LossPattern{"unable to find geometry for id", "meshes dropped"},
    // FBX: geometry of a kind assimp does not convert.
    LossPattern{"ignoring unrecognized geometry", "meshes dropped"},
    LossPattern{"skipping null geometry", "meshes dropped"},
};

std::string lowerCase(std::string_view text) {
  std::string lower(text);
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  return lower;
}

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f%%", 100 * fraction);
  return text;
}

}  // namespace

std::optional<std::string_view> geometryLostIn(std::string_view assimpMessage) {
  const std::string lower = lowerCase(assimpMessage);
  for (const LossPattern& pattern : kLossPatterns)
    if (lower.find(pattern.words) != std::string::npos) return pattern.lost;
  return std::nullopt;
}

std::optional<std::string> unusedVertexLoss(std::size_t unused, std::size_t vertices) {
  if (vertices == 0) return std::nullopt;
  const double fraction = double(unused) / double(vertices);
  if (fraction <= kMaxUnusedVertexFraction) return std::nullopt;
  return cat(unused, " of ", vertices, " vertices (", percent(fraction), ") are used by no face");
}

void settleLosses(const std::string& file, const std::vector<std::string>& losses, bool accept,
                  std::vector<std::string>& warnings) {
  if (losses.empty()) return;
  std::string list;
  for (const std::string& loss : losses) list += cat(list.empty() ? "" : "; ", loss);
  if (!accept)
    throw Error(cat(file, ": the import lost geometry: ", list,
                    ". Refused: a body made of what is left is not the file's body "
                    "(--accept-lossy-import or settings.import.accept_lossy imports it anyway)"));
  warnings.push_back(cat(file, ": the import lost geometry: ", list,
                         "; imported what is left (lossy import accepted)"));
}

}  // namespace softbake
