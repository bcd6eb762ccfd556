#pragma once
/// Geometry an import lost without failing: faces assimp dropped and only logged, vertices no face
/// uses, a file holding fewer rows than its header declares. A body built from what is left is a
/// different body (an open box, a three-particle cow), so such an import is refused unless the
/// user accepts the loss, and then it is a warning.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace softbake {

/// Above this fraction of a file's vertices used by no face, faces were lost (a PLY whose strips
/// assimp skips leaves all but three vertices unused); below it, they are strays of a scan.
inline constexpr double kMaxUnusedVertexFraction = 0.1;

/// What an assimp warning or error says was lost ("faces dropped"), or nothing when the message
/// loses no geometry (an ignored animation, a newer FBX version). Matched on assimp 5.2's wording.
std::optional<std::string_view> geometryLostIn(std::string_view assimpMessage);

/// "2900 of 2903 vertices (99.9%) are used by no face" when more than kMaxUnusedVertexFraction of
/// `vertices` are unused.
std::optional<std::string> unusedVertexLoss(std::size_t unused, std::size_t vertices);

/// With no losses, nothing. Otherwise throws softbake::Error naming `file` and every loss, or,
/// when `accept` is set, adds one warning saying what was lost and that the rest was imported.
void settleLosses(const std::string& file, const std::vector<std::string>& losses, bool accept,
                  std::vector<std::string>& warnings);

}  // namespace softbake
