#pragma once
/// `softbake compare A B`: regression checks for CI. Two rendered frames, two folders of frames
/// (cli/image_set_comparison.hpp), or two bakes (cli/bake_comparison.hpp); a line per frame, an
/// HTML report, a JUnit file, and `--update` to accept new frames as the references. Exit 0 when
/// every frame is within bounds, 1 when one is not (or is missing), 2 on bad input.

#include <filesystem>
#include <optional>
#include <string>

#include "cli/bake_comparison.hpp"

namespace softbake {

struct CompareOptions {
  std::filesystem::path a, b;         ///< reference, new
  std::optional<std::string> metric;  ///< flip (default), pixel or yee
  /// A frame fails when more than failPercent % of its pixels are above `fail`, or its mean
  /// error is above failMean; the same for warnings. Unset: the metric's defaults.
  std::optional<double> fail, failPercent, failMean, warn, warnPercent, warnMean;
  std::optional<int> align;  ///< pixels an edge may move
  /// The pixel metric's thresholds under their old names: `fail` and `failPercent` / 100.
  std::optional<int> tolerance;
  std::optional<double> maxFraction;
  std::optional<std::filesystem::path> diff;    ///< heat maps: a PNG, or a folder for folders
  std::optional<std::filesystem::path> report;  ///< the HTML report's folder
  std::optional<std::filesystem::path> junit;   ///< the JUnit XML file
  bool update = false;                          ///< accept the new frames as references
  BakeThresholds bake;
};

int compareCommand(const CompareOptions& options);

}  // namespace softbake
