#include "cli/image_metrics.hpp"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "cli/flip.hpp"
#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// Per pixel and channel, the least and the most `image` holds within `align` pixels in x and y
/// (a running minimum and maximum, across then down).
template <std::size_t N>
struct Envelope {
  std::vector<std::array<float, N>> low, high;
};
template <std::size_t N>
Envelope<N> envelopeOf(const std::vector<std::array<float, N>>& image, int width, int height,
                       int align) {
  const auto pass = [&](const std::vector<std::array<float, N>>& in, bool across, bool lowest) {
    std::vector<std::array<float, N>> out(in.size());
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        std::array<float, N> v = in[std::size_t(y) * std::size_t(width) + std::size_t(x)];
        for (int k = -align; k <= align; ++k) {
          const int qx = across ? x + k : x, qy = across ? y : y + k;
          if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
          const std::array<float, N>& q =
              in[std::size_t(qy) * std::size_t(width) + std::size_t(qx)];
          for (std::size_t c = 0; c < N; ++c)
            v[c] = lowest ? std::min(v[c], q[c]) : std::max(v[c], q[c]);
        }
        out[std::size_t(y) * std::size_t(width) + std::size_t(x)] = v;
      }
    return out;
  };
  return {pass(pass(image, true, true), false, true), pass(pass(image, true, false), false, false)};
}

/// The per-pixel error of `candidate` against `reference`, where an edge may move by `align`
/// pixels: each pixel is compared with the nearest value, channel by channel, between the least
/// and the most the other image holds within that distance, both ways, and the larger error
/// counts. An antialiased edge moved by any fraction of a pixel up to `align` takes values between
/// its neighbours', so it matches; a body that moved further leaves pixels no neighbour explains.
template <std::size_t N, class Error>
std::vector<float> alignedErrorMap(const std::vector<std::array<float, N>>& reference,
                                   const std::vector<std::array<float, N>>& candidate, int width,
                                   int height, int align, const Error& error) {
  std::vector<float> map(reference.size());
  if (align <= 0) {
    for (std::size_t p = 0; p < map.size(); ++p) map[p] = error(reference[p], candidate[p]);
    return map;
  }
  const Envelope<N> a = envelopeOf(reference, width, height, align),
                    b = envelopeOf(candidate, width, height, align);
  const auto nearest = [](const std::array<float, N>& v, const std::array<float, N>& low,
                          const std::array<float, N>& high) {
    std::array<float, N> out;
    for (std::size_t c = 0; c < N; ++c) out[c] = std::clamp(v[c], low[c], high[c]);
    return out;
  };
  for (std::size_t p = 0; p < map.size(); ++p)
    map[p] = std::max(error(reference[p], nearest(reference[p], b.low[p], b.high[p])),
                      error(candidate[p], nearest(candidate[p], a.low[p], a.high[p])));
  return map;
}

/// Yee's metric wants linear light.
OIIO::ImageBuf linearImageBuf(const ColorImage& image) {
  OIIO::ImageBuf buffer(OIIO::ImageSpec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT));
  std::vector<float> linear(image.rgb.size());
  std::transform(image.rgb.begin(), image.rgb.end(), linear.begin(), srgbToLinear);
  buffer.set_pixels(OIIO::ROI(0, image.width, 0, image.height, 0, 1, 0, 3), OIIO::TypeDesc::FLOAT,
                    linear.data());
  return buffer;
}

ErrorStatistics statisticsOf(std::vector<float> map, const ImageThresholds& thresholds) {
  ErrorStatistics s;
  s.pixels = map.size();
  if (map.empty()) return s;
  double sum = 0;
  for (const float e : map) {
    sum += e;
    s.max = std::max(s.max, double(e));
    s.overFail += e > thresholds.fail.value;
    s.overWarn += e > thresholds.warn.value;
  }
  s.mean = sum / double(map.size());
  const auto at = map.begin() + std::ptrdiff_t(0.99 * double(map.size() - 1));
  std::nth_element(map.begin(), at, map.end());
  s.p99 = *at;
  return s;
}

bool exceeds(const ErrorStatistics& s, const ErrorLimit& limit, double percentOver) {
  return percentOver > limit.percent || s.mean > limit.mean;
}

double psnrOf(const ColorImage& a, const ColorImage& b) {
  double squared = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = 255.0 * (a.rgb[i] - b.rgb[i]);
    squared += d * d;
  }
  const double mean = squared / double(std::max<std::size_t>(a.rgb.size(), 1));
  return mean == 0 ? kInfinity : 10 * std::log10(255.0 * 255.0 / mean);
}

}  // namespace

std::string_view imageMetricName(ImageMetric metric) {
  switch (metric) {
    case ImageMetric::Flip:
      return "flip";
    case ImageMetric::Pixel:
      return "pixel";
    case ImageMetric::Yee:
      return "yee";
  }
  return "flip";
}

ImageMetric parseImageMetric(std::string_view name) {
  for (const ImageMetric metric : {ImageMetric::Flip, ImageMetric::Pixel, ImageMetric::Yee})
    if (imageMetricName(metric) == name) return metric;
  throw Error(cat("--metric: expected flip, pixel or yee, got '", name, "'"));
}

ImageThresholds defaultThresholds(ImageMetric metric) {
  switch (metric) {
    case ImageMetric::Flip:
      // Measured on the built-in scene's frame 1 at 320×240 (docs/regression.md): noise
      // (multisampling off, the camera moved by half a pixel or one, a body moved by up to one
      // pixel) left no pixel above 0.14 and a mean of 0.0011 at most; a body moved by two pixels
      // put 0.39% of the pixels above 0.3, a body's colour 5% darker a mean of 0.0165.
      return {metric, {0.3, 0.05, 0.01}, {0.2, 0.05, 0.005}, 1};
    case ImageMetric::Pixel:
      return {metric, {8, 0.1, kInfinity}, {8, 0, kInfinity}, 1};
    case ImageMetric::Yee:
      // Yee's failing pixels: up to 0.52% for noise, 1.10% for a body moved by two pixels: a
      // margin of two, which is why flip is the default.
      return {metric, {0, 0.75, kInfinity}, {0, 0.1, kInfinity}, 0};
  }
  return {};
}

ImageComparison compareImages(const ColorImage& reference, const ColorImage& candidate,
                              const ImageThresholds& thresholds) {
  if (reference.width != candidate.width || reference.height != candidate.height)
    throw Error(cat("the images differ in size: ", reference.width, "x", reference.height, " and ",
                    candidate.width, "x", candidate.height));
  const int width = reference.width, height = reference.height;
  const int align = std::max(0, thresholds.align);
  ImageComparison result;
  result.psnr = psnrOf(reference, candidate);
  if (thresholds.metric == ImageMetric::Pixel) {
    // 0–255 per channel; the error is the largest channel difference.
    const auto scaled = [](const ColorImage& image) {
      std::vector<std::array<float, 3>> out(image.pixels());
      for (std::size_t p = 0; p < out.size(); ++p)
        for (std::size_t c = 0; c < 3; ++c) out[p][c] = std::round(255 * image.rgb[3 * p + c]);
      return out;
    };
    std::vector<float> map = alignedErrorMap(
        scaled(reference), scaled(candidate), width, height, align,
        [](const std::array<float, 3>& x, const std::array<float, 3>& y) {
          return std::max({std::abs(x[0] - y[0]), std::abs(x[1] - y[1]), std::abs(x[2] - y[2])});
        });
    result.statistics = statisticsOf(map, thresholds);
    for (float& e : map) e /= 255;
    result.map = std::move(map);
  } else {
    const int flipAlign = thresholds.metric == ImageMetric::Flip ? align : 0;
    result.map = alignedErrorMap(flipFeatures(reference.rgb, width, height),
                                 flipFeatures(candidate.rgb, width, height), width, height,
                                 flipAlign, flipError);
    if (thresholds.metric == ImageMetric::Flip)
      result.statistics = statisticsOf(result.map, thresholds);
  }
  if (thresholds.metric == ImageMetric::Yee) {
    OIIO::ImageBufAlgo::CompareResults yee{};
    const int failing =
        OIIO::ImageBufAlgo::compare_Yee(linearImageBuf(reference), linearImageBuf(candidate), yee);
    if (failing < 0) throw Error("OpenImageIO's compare_Yee failed on these images");
    ErrorStatistics& s = result.statistics;
    s.pixels = reference.pixels();
    s.overFail = s.overWarn = std::size_t(failing);
    s.mean = s.pixels ? double(failing) / double(s.pixels) : 0;
    s.max = failing > 0 ? 1 : 0;
    s.p99 = s.mean > 0.01 ? 1 : 0;
  }
  const ErrorStatistics& s = result.statistics;
  if (exceeds(s, thresholds.fail, s.percentOverFail()))
    result.verdict = Verdict::Fail;
  else if (exceeds(s, thresholds.warn, s.percentOverWarn()))
    result.verdict = Verdict::Warn;
  return result;
}

std::string describe(const ImageComparison& comparison, const ImageThresholds& thresholds) {
  const ErrorStatistics& s = comparison.statistics;
  char psnr[32];
  if (std::isinf(comparison.psnr))
    std::snprintf(psnr, sizeof psnr, "identical");
  else
    std::snprintf(psnr, sizeof psnr, "PSNR %.1f dB", comparison.psnr);
  char line[256];
  if (thresholds.metric == ImageMetric::Yee)
    std::snprintf(line, sizeof line, "yee: %zu pixels (%.4f%%) fail; %s", s.overFail,
                  s.percentOverFail(), psnr);
  else
    std::snprintf(line, sizeof line,
                  "%s: mean %.4g, p99 %.4g, max %.4g; %zu pixels (%.4f%%) over %g; %s",
                  std::string(imageMetricName(thresholds.metric)).c_str(), s.mean, s.p99, s.max,
                  s.overFail, s.percentOverFail(), thresholds.fail.value, psnr);
  return line;
}

Image heatMap(const ColorImage& reference, const std::vector<float>& map) {
  // Dark red, orange, yellow, white at errors 0, 1/3, 2/3 and 1.
  constexpr std::array<std::array<float, 3>, 4> ramp = {
      {{0.5f, 0, 0}, {1, 0.45f, 0}, {1, 0.9f, 0.1f}, {1, 1, 1}}};
  Image out{reference.width, reference.height,
            std::vector<std::uint8_t>(4 * reference.pixels(), 255)};
  for (std::size_t p = 0; p < reference.pixels(); ++p) {
    const float* c = &reference.rgb[3 * p];
    const float grey = 0.3f * (0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]);
    const float e = std::clamp(map[p], 0.0f, 1.0f);
    const float position = e * 3;
    const std::size_t low = std::min<std::size_t>(2, std::size_t(position));
    const float t = position - float(low), strength = std::min(1.0f, 4 * e);
    for (std::size_t k = 0; k < 3; ++k) {
      const float hot = ramp[low][k] + t * (ramp[low + 1][k] - ramp[low][k]);
      out.rgba[4 * p + k] = std::uint8_t(std::lround(255 * (grey + strength * (hot - grey))));
    }
  }
  return out;
}

}  // namespace softbake
