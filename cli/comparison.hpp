#pragma once
/// What a comparison found, item by item (a frame of images, a frame of a bake), in the form the
/// console, the HTML report (cli/html_report.hpp) and the JUnit file (cli/junit_report.hpp) share.

#include <string>
#include <vector>

#include "bake/svg_plot.hpp"

namespace softbake {

/// Exit statuses of `softbake compare` (its own contract, docs/commands.md).
inline constexpr int kCompareSame = 0, kCompareDiffers = 1, kCompareBadInput = 2;

enum class Verdict { Pass, Warn, Fail };

const char* verdictName(Verdict verdict);  ///< "ok", "warn", "DIFFERS"

struct ComparedItem {
  std::string name;  ///< a frame's file name, or "frame 12"
  Verdict verdict = Verdict::Pass;
  std::string summary;               ///< one line, with the numbers
  std::vector<std::string> details;  ///< more lines: per body, first frames over a threshold
  double severity = 0;               ///< larger is worse: orders items of one verdict
  bool missing = false;              ///< a frame one side lacks
  /// Images of the item in the report, relative to its folder; empty when it has none.
  std::string referenceImage, candidateImage, differenceImage;
};

struct Comparison {
  std::string kind;                  ///< "images" or "bakes"
  std::string reference, candidate;  ///< as given
  std::string thresholds;            ///< the thresholds in force, as a sentence
  std::vector<ComparedItem> items;
  std::vector<std::string> notes;  ///< lines for the summary: what was not compared, and why
  std::vector<Plot> plots;
  std::size_t count(Verdict verdict) const;
  Verdict worst() const;
};

/// The items in report order: failures first, then warnings, then passes, each worst first, then
/// by name.
std::vector<const ComparedItem*> reportOrder(const Comparison& comparison);

}  // namespace softbake
