#pragma once
/// The measures `softbake compare` applies to two frames, and their statistics.
///
///  - flip: LDR-FLIP (cli/flip.hpp), the perceived difference per pixel in [0, 1];
///  - pixel: the largest channel difference per pixel, 0–255 (the measure compare always had);
///  - yee: OpenImageIO's ImageBufAlgo::compare_Yee (Yee's perceptual metric), a pass or fail
///    per pixel.
///
/// flip and pixel forgive an edge that moved by up to `align` pixels: each pixel is compared with
/// the nearest of the values (channel by channel, between the least and the most) the other frame
/// holds within that distance, both ways, and the larger of the two errors counts. A camera
/// shifted by a pixel or an edge antialiased differently moves edges by a pixel at most, and an
/// antialiased edge takes values between its neighbours'; a body that moved moves its edges
/// further. docs/regression.md has the measurements behind the defaults.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli/comparison.hpp"
#include "cli/image_file.hpp"

namespace softbake {

enum class ImageMetric { Flip, Pixel, Yee };

std::string_view imageMetricName(ImageMetric metric);
/// "flip", "pixel", "yee".
// Inline: the `softbake` program checks --metric with it without linking the metrics
// (cli/CMakeLists.txt).
inline std::vector<std::string> imageMetricNames() {
  return {"flip", "pixel", "yee"};
}
/// The metric of a name in imageMetricNames(). Throws softbake::Error for any other.
ImageMetric parseImageMetric(std::string_view name);

/// When a frame fails or warns: more than `percent` % of its pixels have an error above `value`,
/// or its mean error is above `mean`.
struct ErrorLimit {
  double value = 0;
  double percent = 0;
  double mean = 0;  ///< +infinity: the mean decides nothing
};

struct ImageThresholds {
  ImageMetric metric = ImageMetric::Flip;
  ErrorLimit fail, warn;
  int align = 1;  ///< pixels an edge may move (flip and pixel)
};

/// The defaults of `metric` (measured on softbake's frames: docs/regression.md).
ImageThresholds defaultThresholds(ImageMetric metric);

struct ErrorStatistics {
  std::size_t pixels = 0;
  double mean = 0, max = 0, p99 = 0;  ///< of the per-pixel error; yee: of 0 and 1
  std::size_t overFail = 0;           ///< pixels above the fail value (yee: failing pixels)
  std::size_t overWarn = 0;           ///< pixels above the warn value
  double percentOverFail() const { return pixels ? 100.0 * double(overFail) / double(pixels) : 0; }
  double percentOverWarn() const { return pixels ? 100.0 * double(overWarn) / double(pixels) : 0; }
};

struct ImageComparison {
  ErrorStatistics statistics;  ///< of the thresholds' metric
  Verdict verdict = Verdict::Pass;
  double psnr = 0;  ///< dB over RGB at 8 bits; +infinity for identical frames
  /// The thresholds' metric per pixel, scaled to [0, 1] (pixel: /255); yee: FLIP's, since Yee's
  /// gives no map. For the heat map.
  std::vector<float> map;
};

/// Compares `candidate` with `reference`. Throws softbake::Error when their sizes differ.
ImageComparison compareImages(const ColorImage& reference, const ColorImage& candidate,
                              const ImageThresholds& thresholds);

/// The statistics as one line: "flip: mean 0.0031, p99 0.079, max 0.26; 12 pixels (0.0156%)
/// over 0.3".
std::string describe(const ImageComparison& comparison, const ImageThresholds& thresholds);

/// The difference as a picture: the reference dimmed to grey, and over it `map` from dark red
/// through orange and yellow to white, stronger as the error grows (full at a quarter and up).
Image heatMap(const ColorImage& reference, const std::vector<float>& map);

}  // namespace softbake
