#include "cli/compare_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <vector>

#include "cli/image_compare.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

constexpr int kWithinBounds = 0, kDiffers = 1, kBadInput = 2;

std::string describe(const ImageDifference& d) {
  char psnr[32];
  if (std::isinf(d.psnr))
    std::snprintf(psnr, sizeof psnr, "identical");
  else
    std::snprintf(psnr, sizeof psnr, "PSNR %.1f dB", d.psnr);
  char line[160];
  std::snprintf(line, sizeof line,
                "%.4f%% of pixels over tolerance (%zu), largest difference %d, %s",
                100 * d.fractionOver(), d.pixelsOverTolerance, d.largestDifference, psnr);
  return line;
}

/// Compares one pair; prints one line starting with `label`. Returns the exit code for the pair.
int comparePair(const std::string& label, const fs::path& a, const fs::path& b,
                const CompareOptions& options, const std::optional<fs::path>& diffPath) {
  Image diff;
  const ImageDifference d =
      compareImages(loadImage(a), loadImage(b), options.tolerance, diffPath ? &diff : nullptr);
  const bool within = d.fractionOver() <= options.maxFraction;
  std::printf("%s: %s: %s\n", label.c_str(), within ? "ok" : "DIFFERS", describe(d).c_str());
  if (diffPath && !within) writePng(*diffPath, diff);
  return within ? kWithinBounds : kDiffers;
}

std::set<std::string> pngNames(const fs::path& folder) {
  std::set<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    std::string extension = entry.path().extension().string();
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (entry.is_regular_file() && extension == ".png")
      names.insert(entry.path().filename().string());
  }
  return names;
}

int compareFolders(const CompareOptions& options) {
  const std::set<std::string> inA = pngNames(options.a), inB = pngNames(options.b);
  if (inA.empty()) throw Error(cat(options.a.string(), ": no PNG frames in this folder"));
  if (options.diff) makeDirectories(*options.diff);
  int worst = kWithinBounds;
  std::size_t differing = 0, missing = 0;
  std::set<std::string> all = inA;
  all.insert(inB.begin(), inB.end());
  for (const std::string& name : all) {
    if (!inA.count(name) || !inB.count(name)) {
      std::printf("%s: missing in %s\n", name.c_str(),
                  (inA.count(name) ? options.b : options.a).string().c_str());
      ++missing;
      continue;
    }
    std::optional<fs::path> diffPath;
    if (options.diff) diffPath = *options.diff / name;
    const int result = comparePair(name, options.a / name, options.b / name, options, diffPath);
    differing += result != kWithinBounds;
    worst = std::max(worst, result);
  }
  std::printf(
      "%zu frames: %zu within bounds, %zu differ, %zu missing (tolerance %d, max fraction %g)\n",
      all.size(), all.size() - differing - missing, differing, missing, options.tolerance,
      options.maxFraction);
  return missing ? kBadInput : worst;
}

}  // namespace

int compareCommand(const CompareOptions& options) {
  try {
    std::error_code error;
    const bool folderA = fs::is_directory(options.a, error),
               folderB = fs::is_directory(options.b, error);
    if (folderA != folderB)
      throw Error(cat("compare two images or two folders, not one of each: ", options.a.string(),
                      ", ", options.b.string()));
    if (folderA) return compareFolders(options);
    return comparePair(options.b.filename().string(), options.a, options.b, options, options.diff);
  } catch (const Error& error) {
    std::fflush(stdout);
    std::fprintf(stderr, "softbake: error: %s\n", error.what());
  } catch (const fs::filesystem_error& error) {
    std::fflush(stdout);
    std::fprintf(stderr, "softbake: error: %s\n", error.what());
  }
  return kBadInput;
}

}  // namespace softbake
