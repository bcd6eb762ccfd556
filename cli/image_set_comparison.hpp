#pragma once
/// Two frames, or two folders of frames matched by name (without the extension, so EXR
/// references can stand for PNG renders), compared with the image metrics. A frame one folder
/// lacks is a failure that names it.

#include <filesystem>
#include <optional>
#include <vector>

#include "cli/comparison.hpp"
#include "cli/image_metrics.hpp"

namespace softbake {

/// One frame: where it is on either side (empty where it is missing).
struct FramePair {
  std::optional<std::filesystem::path> reference, candidate;
  Verdict verdict = Verdict::Pass;
};

struct ImageSetComparison {
  Comparison comparison;
  std::vector<FramePair> frames;  ///< in the order of comparison.items
};

/// Where compare writes pictures of the differences.
struct ImageOutputs {
  /// A heat map of each frame that does not pass: a PNG for two frames, a folder for folders.
  std::optional<std::filesystem::path> diff;
  /// The report's folder: every frame's reference, new frame and heat map go to its images/.
  std::optional<std::filesystem::path> report;
};

/// Compares `candidate` with `reference`, two image files or two folders. Throws softbake::Error
/// for bad input: a file and a folder, a missing file, an empty folder, two frames of one name in
/// a folder, an unreadable image, images of different sizes (naming both files).
ImageSetComparison compareImageSets(const std::filesystem::path& reference,
                                    const std::filesystem::path& candidate,
                                    const ImageThresholds& thresholds, const ImageOutputs& outputs);

/// The thresholds as a sentence, for the report and the JUnit file.
std::string describeThresholds(const ImageThresholds& thresholds);

}  // namespace softbake
