#include "cli/image_set_comparison.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>

#include <tbb/parallel_for.h>

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace fs = std::filesystem;

namespace {

/// The image files of `folder` by stem: the formats frames come in.
std::map<std::string, fs::path> frameFiles(const fs::path& folder) {
  static const std::vector<std::string> extensions = {".png",  ".exr", ".tif",
                                                      ".tiff", ".jpg", ".jpeg"};
  std::map<std::string, fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    std::string extension = entry.path().extension().string();
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (!entry.is_regular_file() ||
        std::find(extensions.begin(), extensions.end(), extension) == extensions.end())
      continue;
    const auto [at, added] = files.emplace(entry.path().stem().string(), entry.path());
    if (!added)
      throw Error(cat(folder.string(), ": two frames named '", at->first, "': ",
                      at->second.filename().string(), " and ", entry.path().filename().string()));
  }
  if (files.empty())
    throw Error(cat(folder.string(), ": no frames (PNG, EXR, TIFF or JPEG) in this folder"));
  return files;
}

std::string limitText(const ErrorLimit& limit, bool yee) {
  std::string text =
      yee ? cat("more than ", limit.percent, "% of the pixels fail")
          : cat("more than ", limit.percent, "% of the pixels are above ", limit.value);
  if (std::isfinite(limit.mean)) text += cat(" or the mean is above ", limit.mean);
  return text;
}

class FrameComparer {
 public:
  FrameComparer(const ImageThresholds& thresholds, const ImageOutputs& outputs)
      : thresholds_(thresholds), outputs_(outputs) {}

  /// Compares one pair; writes its pictures. `diffPath`: where its heat map goes, if anywhere.
  ComparedItem compare(const std::string& name, const fs::path& reference,
                       const fs::path& candidate, const std::optional<fs::path>& diffPath) {
    const ColorImage a = readImage(reference), b = readImage(candidate);
    ImageComparison result;
    try {
      result = compareImages(a, b, thresholds_);
    } catch (const Error& error) {
      throw Error(cat(reference.string(), " and ", candidate.string(), ": ", error.what()));
    }
    ComparedItem item;
    item.name = name;
    item.verdict = result.verdict;
    item.summary = describe(result, thresholds_);
    const ErrorStatistics& s = result.statistics;
    item.severity = thresholds_.metric == ImageMetric::Yee
                        ? s.percentOverFail()
                        : s.percentOverFail() / std::max(thresholds_.fail.percent, 1e-9) +
                              s.mean / std::max(thresholds_.fail.mean, 1e-9);
    if (thresholds_.metric != ImageMetric::Yee)
      item.details.push_back(cat(s.overWarn, " pixels (", s.percentOverWarn(),
                                 "%) above the warn value ", thresholds_.warn.value));
    Image heat;
    if (diffPath || outputs_.report) heat = heatMap(a, result.map);
    if (diffPath && result.verdict != Verdict::Pass) writePng(*diffPath, heat);
    if (outputs_.report) {
      const std::string stem = fs::path(name).stem().string();
      item.referenceImage = writeReportImage(stem + ".ref.png", toImage(a));
      item.candidateImage = writeReportImage(stem + ".new.png", toImage(b));
      item.differenceImage = writeReportImage(stem + ".diff.png", heat);
    }
    return item;
  }

  /// A frame only one side has: a failure, and its one picture.
  ComparedItem missing(const std::string& name, const fs::path& present, bool inReference,
                       const fs::path& otherFolder) {
    ComparedItem item;
    item.name = name;
    item.verdict = Verdict::Fail;
    item.summary = inReference ? cat("missing in ", otherFolder.string())
                               : cat("not in the reference folder ", otherFolder.string());
    item.severity = 1e300;
    item.missing = true;
    if (outputs_.report) {
      const std::string file =
          fs::path(name).stem().string() + (inReference ? ".ref.png" : ".new.png");
      (inReference ? item.referenceImage : item.candidateImage) =
          writeReportImage(file, toImage(readImage(present)));
    }
    return item;
  }

 private:
  std::string writeReportImage(const std::string& file, const Image& image) {
    writePng(*outputs_.report / "images" / file, image);
    return "images/" + file;
  }

  const ImageThresholds& thresholds_;
  const ImageOutputs& outputs_;
};

}  // namespace

std::string describeThresholds(const ImageThresholds& t) {
  const bool yee = t.metric == ImageMetric::Yee;
  std::string text = cat(imageMetricName(t.metric), ": a frame fails when ", limitText(t.fail, yee),
                         "; warns when ", limitText(t.warn, yee));
  if (!yee) text += cat("; edges may move by ", t.align, t.align == 1 ? " pixel" : " pixels");
  return text;
}

ImageSetComparison compareImageSets(const fs::path& reference, const fs::path& candidate,
                                    const ImageThresholds& thresholds,
                                    const ImageOutputs& outputs) {
  std::error_code error;
  for (const fs::path& path : {reference, candidate})
    if (!fs::exists(path, error)) throw Error(cat(path.string(), ": no such file or folder"));
  const bool folderA = fs::is_directory(reference, error),
             folderB = fs::is_directory(candidate, error);
  if (folderA != folderB)
    throw Error(cat("compare two images or two folders, not one of each: ", reference.string(),
                    ", ", candidate.string()));
  ImageSetComparison result;
  result.comparison.kind = "images";
  result.comparison.reference = reference.string();
  result.comparison.candidate = candidate.string();
  result.comparison.thresholds = describeThresholds(thresholds);
  FrameComparer comparer(thresholds, outputs);
  if (outputs.report) makeDirectories(*outputs.report / "images");
  if (!folderA) {
    result.comparison.items.push_back(
        comparer.compare(candidate.filename().string(), reference, candidate, outputs.diff));
    result.frames.push_back({reference, candidate, result.comparison.items.back().verdict});
    return result;
  }

  const std::map<std::string, fs::path> inA = frameFiles(reference), inB = frameFiles(candidate);
  if (outputs.diff) makeDirectories(*outputs.diff);
  std::map<std::string, FramePair> all;
  for (const auto& [stem, path] : inA) all[stem].reference = path;
  for (const auto& [stem, path] : inB) all[stem].candidate = path;
  for (const auto& [stem, pair] : all) result.frames.push_back(pair);
  // Frames are independent: compared on all cores, listed in name order.
  result.comparison.items.resize(result.frames.size());
  tbb::parallel_for(std::size_t(0), result.frames.size(), [&](std::size_t i) {
    FramePair& pair = result.frames[i];
    const fs::path& present = pair.reference ? *pair.reference : *pair.candidate;
    const std::string name = present.filename().string();
    ComparedItem& item = result.comparison.items[i];
    if (!pair.reference || !pair.candidate) {
      item = comparer.missing(name, present, bool(pair.reference),
                              pair.reference ? candidate : reference);
    } else {
      std::optional<fs::path> diffPath;
      if (outputs.diff) diffPath = *outputs.diff / (present.stem().string() + ".png");
      item = comparer.compare(name, *pair.reference, *pair.candidate, diffPath);
    }
    pair.verdict = item.verdict;
  });
  return result;
}

}  // namespace softbake
