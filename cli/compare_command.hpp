#pragma once
/// `softbake compare A B`: image regression for rendered frames, one pair of PNGs or two folders
/// of frames. Exit 0 when every frame is within bounds, 1 when one is not, 2 on bad input (a
/// missing file or frame, images of different sizes).

#include <filesystem>
#include <optional>
#include <string>

namespace softbake {

struct CompareOptions {
  std::filesystem::path a, b;
  int tolerance = 8;  ///< largest channel difference (0–255) a pixel may have and still match
  double maxFraction = 0.001;                 ///< fraction of pixels allowed over the tolerance
  std::optional<std::filesystem::path> diff;  ///< a PNG, or a folder when comparing folders
};

int compareCommand(const CompareOptions& options);

}  // namespace softbake
