#include "cli/flip.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "cli/image_file.hpp"

namespace softbake {

namespace {

constexpr double kPi = 3.14159265358979323846;

using Color = std::array<float, 3>;

// Linear sRGB (D65) to CIE XYZ and back (IEC 61966-2-1).
Color linearRgbToXyz(const Color& c) {
  return {0.4124564f * c[0] + 0.3575761f * c[1] + 0.1804375f * c[2],
          0.2126729f * c[0] + 0.7151522f * c[1] + 0.0721750f * c[2],
          0.0193339f * c[0] + 0.1191920f * c[1] + 0.9503041f * c[2]};
}
Color xyzToLinearRgb(const Color& c) {
  return {3.2404542f * c[0] - 1.5371385f * c[1] - 0.4985314f * c[2],
          -0.9692660f * c[0] + 1.8760108f * c[1] + 0.0415560f * c[2],
          0.0556434f * c[0] - 0.2040259f * c[1] + 1.0572252f * c[2]};
}

/// The reference white: XYZ of linear RGB (1, 1, 1).
const Color kWhite = linearRgbToXyz({1, 1, 1});

/// YyCxCz (§4.1): CIELAB without its cube root, a linear opponent space in which filtering by the
/// contrast sensitivity functions is meaningful.
Color xyzToYcxcz(const Color& c) {
  const float x = c[0] / kWhite[0], y = c[1] / kWhite[1], z = c[2] / kWhite[2];
  return {116 * y - 16, 500 * (x - y), 200 * (y - z)};
}
Color ycxczToXyz(const Color& c) {
  const float y = (c[0] + 16) / 116, x = y + c[1] / 500, z = y - c[2] / 200;
  return {x * kWhite[0], y * kWhite[1], z * kWhite[2]};
}

float labF(float t) {
  constexpr float delta = 6.0f / 29;
  return t > delta * delta * delta ? std::cbrt(t) : t / (3 * delta * delta) + 4.0f / 29;
}

/// CIELAB with the Hunt effect (chroma seen weaker at low luminance): a and b scaled by 0.01·L.
Color huntLab(const Color& linearRgb) {
  const Color xyz = linearRgbToXyz(linearRgb);
  const float fx = labF(xyz[0] / kWhite[0]), fy = labF(xyz[1] / kWhite[1]),
              fz = labF(xyz[2] / kWhite[2]);
  const float l = 116 * fy - 16;
  return {l, 0.01f * l * 500 * (fx - fy), 0.01f * l * 200 * (fy - fz)};
}

/// HyAB (Abasi et al. 2020): city-block in lightness, Euclidean in chroma; better than ΔE for
/// large differences.
float hyab(const float* p, const float* q) {
  const float da = p[1] - q[1], db = p[2] - q[2];
  return std::abs(p[0] - q[0]) + std::sqrt(da * da + db * db);
}

// The colour error's compression and remapping (§4.1): q_c, and the break point p_c of the
// largest error below which errors map linearly onto [0, p_t].
constexpr float kColorExponent = 0.7f, kBreakFraction = 0.4f, kBreakValue = 0.95f;
// The feature error's exponent q_f, and the feature width w in degrees (§4.2).
constexpr float kFeatureExponent = 0.5f;
constexpr double kFeatureWidthDegrees = 0.082;

/// The largest colour error: between pure green and pure blue, the farthest apart of the sRGB
/// gamut in Hunt-adjusted HyAB.
const float kMaxColorError = [] {
  const Color green = huntLab({0, 1, 0}), blue = huntLab({0, 0, 1});
  return std::pow(hyab(green.data(), blue.data()), kColorExponent);
}();

using Kernel = std::vector<float>;  ///< 2r + 1 taps, centre at r

/// Convolves `image` (one channel) by `alongX` across and `alongY` down, edges clamped.
std::vector<float> convolve(const std::vector<float>& image, int width, int height,
                            const Kernel& alongX, const Kernel& alongY) {
  std::vector<float> across(image.size()), out(image.size());
  const int rx = int(alongX.size() / 2), ry = int(alongY.size() / 2);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      float sum = 0;
      for (int k = -rx; k <= rx; ++k)
        sum += alongX[std::size_t(k + rx)] *
               image[std::size_t(y) * width + std::size_t(std::clamp(x + k, 0, width - 1))];
      across[std::size_t(y) * width + x] = sum;
    }
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      float sum = 0;
      for (int k = -ry; k <= ry; ++k)
        sum += alongY[std::size_t(k + ry)] *
               across[std::size_t(std::clamp(y + k, 0, height - 1)) * width + x];
      out[std::size_t(y) * width + x] = sum;
    }
  return out;
}

/// One channel's contrast sensitivity as a spatial filter (§4.1, table 1): a1·√(π/b1)·e^(−π²x²/b1)
/// plus the same with a2, b2, x in degrees; in two dimensions each term is a Gaussian of variance
/// b/(2π²) with weight a·π/b. Its radius covers three of the widest term's deviations.
struct ContrastSensitivity {
  float a1, b1, a2, b2;
};
constexpr ContrastSensitivity kSensitivity[3] = {
    {1, 0.0047f, 0, 1e-5f},        // achromatic (Yy)
    {1, 0.0053f, 0, 1e-5f},        // red–green (Cx)
    {34.1f, 0.04f, 13.5f, 0.025f}  // blue–yellow (Cz)
};

std::vector<float> filterBySensitivity(const std::vector<float>& channel, int width, int height,
                                       const ContrastSensitivity& s, double pixelsPerDegree) {
  const double widest = std::max(s.b1, s.b2);
  const int radius = int(std::ceil(3 * std::sqrt(widest / (2 * kPi * kPi)) * pixelsPerDegree));
  const auto term = [&](float b) {
    Kernel g(std::size_t(2 * radius + 1));
    for (int x = -radius; x <= radius; ++x) {
      const double degrees = x / pixelsPerDegree;
      g[std::size_t(x + radius)] = float(std::exp(-kPi * kPi * degrees * degrees / b));
    }
    return g;
  };
  const auto weightOf = [](float a, float b, const Kernel& g) {
    double sum = 0;
    for (float v : g) sum += v;
    return a * kPi / b * sum * sum;  // the term's discrete 2D sum
  };
  // The kernel sums to 1 over its taps, so a flat region keeps its value.
  const Kernel g1 = term(s.b1), g2 = term(s.b2);
  const double w1 = weightOf(s.a1, s.b1, g1), w2 = s.a2 == 0 ? 0 : weightOf(s.a2, s.b2, g2);
  std::vector<float> out = convolve(channel, width, height, g1, g1);
  const double k1 = s.a1 * kPi / s.b1 / (w1 + w2);
  if (s.a2 == 0) {
    for (float& v : out) v = float(k1 * v);
    return out;
  }
  const std::vector<float> second = convolve(channel, width, height, g2, g2);
  const double k2 = s.a2 * kPi / s.b2 / (w1 + w2);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = float(k1 * out[i] + k2 * second[i]);
  return out;
}

/// Scales `kernel` so that its positive taps sum to 1 and its negative ones to −1 (§4.2), so an
/// edge or point of full contrast answers 1 whatever the width.
void balance(Kernel& kernel) {
  float positive = 0, negative = 0;
  for (float v : kernel) (v > 0 ? positive : negative) += v;
  for (float& v : kernel) v = v > 0 ? v / positive : v / -negative;
}

}  // namespace

std::vector<FlipPixel> flipFeatures(const std::vector<float>& rgb, int width, int height,
                                    const FlipViewing& viewing) {
  const std::size_t pixels = std::size_t(width) * std::size_t(height);
  std::vector<FlipPixel> f(pixels);
  std::array<std::vector<float>, 3> opponent;
  for (auto& channel : opponent) channel.resize(pixels);
  std::vector<float> luminance(pixels);
  for (std::size_t p = 0; p < pixels; ++p) {
    const Color linear = {srgbToLinear(rgb[3 * p]), srgbToLinear(rgb[3 * p + 1]),
                          srgbToLinear(rgb[3 * p + 2])};
    const Color xyz = linearRgbToXyz(linear);
    const Color ycxcz = xyzToYcxcz(xyz);
    for (int c = 0; c < 3; ++c) opponent[std::size_t(c)][p] = ycxcz[std::size_t(c)];
    luminance[p] = xyz[1] / kWhite[1];  // (Yy + 16) / 116: the achromatic channel in [0, 1]
  }

  // Colour: filter in YyCxCz, back to linear RGB clamped to the gamut, then Hunt-adjusted Lab.
  for (int c = 0; c < 3; ++c)
    opponent[std::size_t(c)] = filterBySensitivity(opponent[std::size_t(c)], width, height,
                                                   kSensitivity[c], viewing.pixelsPerDegree);
  for (std::size_t p = 0; p < pixels; ++p) {
    Color linear = xyzToLinearRgb(ycxczToXyz({opponent[0][p], opponent[1][p], opponent[2][p]}));
    for (float& v : linear) v = std::clamp(v, 0.0f, 1.0f);
    const Color lab = huntLab(linear);
    std::copy(lab.begin(), lab.end(), f[p].begin());
  }

  // Features: first and second derivatives of a Gaussian as wide as the feature width.
  const double sigma = 0.5 * kFeatureWidthDegrees * viewing.pixelsPerDegree;
  const int radius = int(std::ceil(3 * sigma));
  Kernel gauss(std::size_t(2 * radius + 1)), first(gauss.size()), second(gauss.size());
  float sum = 0;
  for (int x = -radius; x <= radius; ++x) {
    const auto i = std::size_t(x + radius);
    gauss[i] = float(std::exp(-x * x / (2 * sigma * sigma)));
    sum += gauss[i];
  }
  for (int x = -radius; x <= radius; ++x) {
    const auto i = std::size_t(x + radius);
    gauss[i] /= sum;
    first[i] = float(-x * gauss[i]);
    second[i] = float((x * x / (sigma * sigma) - 1) * gauss[i]);
  }
  balance(first);
  balance(second);
  const auto magnitude = [&](const Kernel& derivative) {
    const std::vector<float> dx = convolve(luminance, width, height, derivative, gauss);
    const std::vector<float> dy = convolve(luminance, width, height, gauss, derivative);
    std::vector<float> m(pixels);
    for (std::size_t p = 0; p < pixels; ++p) m[p] = std::sqrt(dx[p] * dx[p] + dy[p] * dy[p]);
    return m;
  };
  const std::vector<float> edge = magnitude(first), point = magnitude(second);
  for (std::size_t p = 0; p < pixels; ++p) {
    f[p][3] = edge[p];
    f[p][4] = point[p];
  }
  return f;
}

float flipError(const FlipPixel& reference, const FlipPixel& test) {
  const float difference = std::pow(hyab(reference.data(), test.data()), kColorExponent);
  const float breakError = kBreakFraction * kMaxColorError;
  const float color = difference < breakError
                          ? kBreakValue / breakError * difference
                          : kBreakValue + (difference - breakError) /
                                              (kMaxColorError - breakError) * (1 - kBreakValue);
  const float featureDifference =
      std::max(std::abs(reference[3] - test[3]), std::abs(reference[4] - test[4])) /
      std::sqrt(2.0f);
  const float feature = std::pow(std::min(featureDifference, 1.0f), kFeatureExponent);
  return std::min(1.0f, std::pow(std::min(color, 1.0f), 1 - feature));
}

}  // namespace softbake
