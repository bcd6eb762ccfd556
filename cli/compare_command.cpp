#include "cli/compare_command.hpp"

#include <cstdio>
#include <vector>

#include "cli/bake_sequence.hpp"
#include "cli/html_report.hpp"
#include "cli/image_set_comparison.hpp"
#include "cli/junit_report.hpp"
#include "cli/reference_update.hpp"
#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

ImageThresholds imageThresholds(const CompareOptions& options) {
  const bool legacy = options.tolerance || options.maxFraction;
  const ImageMetric metric = options.metric ? parseImageMetric(*options.metric)
                             : legacy       ? ImageMetric::Pixel
                                            : ImageMetric::Flip;
  if (legacy && metric != ImageMetric::Pixel)
    throw Error(
        cat("--tolerance and --max-fraction are the pixel metric's thresholds; for --metric ",
            imageMetricName(metric), " use --fail and --fail-percent"));
  ImageThresholds t = defaultThresholds(metric);
  // The old flags keep their old meaning: every pixel against the same pixel.
  if (legacy) t.align = 0;
  if (options.tolerance) t.fail.value = *options.tolerance;
  if (options.maxFraction) t.fail.percent = 100 * *options.maxFraction;
  if (options.fail) t.fail.value = *options.fail;
  if (options.failPercent) t.fail.percent = *options.failPercent;
  if (options.failMean) t.fail.mean = *options.failMean;
  if (options.warn) t.warn.value = *options.warn;
  if (options.warnPercent) t.warn.percent = *options.warnPercent;
  if (options.warnMean) t.warn.mean = *options.warnMean;
  if (options.align) t.align = *options.align;
  return t;
}

void print(const Comparison& comparison) {
  std::size_t missing = 0;
  for (const ComparedItem& item : comparison.items) {
    std::printf("%s: %s: %s\n", item.name.c_str(), verdictName(item.verdict), item.summary.c_str());
    missing += item.missing;
  }
  for (const std::string& note : comparison.notes) std::printf("%s\n", note.c_str());
  const std::size_t fails = comparison.count(Verdict::Fail);
  const bool one = comparison.items.size() == 1;
  const char* unit =
      comparison.kind == "images" ? (one ? "frame" : "frames") : (one ? "item" : "items");
  std::printf("%zu %s: %zu within bounds (%zu warn), %zu differ (%zu of them missing); %s\n",
              comparison.items.size(), unit, comparison.items.size() - fails,
              comparison.count(Verdict::Warn), fails, missing, comparison.thresholds.c_str());
}

int compare(const CompareOptions& options) {
  const bool bakeA = BakeSequence::isBake(options.a), bakeB = BakeSequence::isBake(options.b);
  Comparison comparison;
  std::vector<FramePair> frames;
  if (bakeA || bakeB) {
    if (!bakeA || !bakeB)
      throw Error(cat(
          "compare two bakes or two sets of images, not one of each: ", options.a.string(), " is ",
          bakeA ? "" : "not ", "a bake, ", options.b.string(), " is ", bakeB ? "" : "not ", "one"));
    if (options.update || options.diff)
      throw Error("--update and --diff are for images; bakes are compared, not replaced");
    comparison = compareBakes(options.a, options.b, options.bake);
  } else {
    ImageSetComparison images = compareImageSets(options.a, options.b, imageThresholds(options),
                                                 {options.diff, options.report});
    comparison = std::move(images.comparison);
    frames = std::move(images.frames);
  }
  print(comparison);
  if (options.report) {
    writeHtmlReport(*options.report, comparison);
    std::printf("report: %s\n", (*options.report / "index.html").string().c_str());
  }
  if (options.junit) {
    writeJunit(*options.junit, comparison);
    std::printf("junit: %s\n", options.junit->string().c_str());
  }
  if (options.update) {
    const std::vector<std::string> changes = acceptNewFrames(options.a, frames);
    for (const std::string& change : changes) std::printf("%s\n", change.c_str());
    std::printf("accepted the new frames as references in %s: %zu files changed\n",
                options.a.string().c_str(), changes.size());
    return kCompareSame;
  }
  return comparison.worst() == Verdict::Fail ? kCompareDiffers : kCompareSame;
}

}  // namespace

int compareCommand(const CompareOptions& options) {
  try {
    return compare(options);
  } catch (const Error& error) {
    std::fflush(stdout);
    std::fprintf(stderr, "softbake: error: %s\n", error.what());
  } catch (const fs::filesystem_error& error) {
    std::fflush(stdout);
    std::fprintf(stderr, "softbake: error: %s\n", error.what());
  }
  return kCompareBadInput;
}

}  // namespace softbake
