#pragma once
/// Reading frames for comparison (PNG, EXR, TIFF and whatever else OpenImageIO reads) and writing
/// the PNGs compare makes (difference images, heat maps).

#include <cstdint>
#include <filesystem>
#include <vector>

namespace softbake {

/// A frame as it is shown: 3 floats per pixel, rows top to bottom, sRGB-encoded values in [0, 1].
/// Linear images (EXR, float TIFF) are clamped to [0, 1] and encoded, as a display would show
/// them; alpha is dropped, since rendered frames are opaque; grey images are spread to RGB.
struct ColorImage {
  int width = 0, height = 0;
  std::vector<float> rgb;
  std::size_t pixels() const { return std::size_t(width) * std::size_t(height); }
};

/// Reads an image through OpenImageIO. Throws softbake::Error naming the file and what is wrong
/// (missing, not an image, truncated or otherwise unreadable).
ColorImage readImage(const std::filesystem::path& path);

/// The sRGB transfer function (IEC 61966-2-1) one way and the other, for values in [0, 1]:
/// display-encoded to linear light, and linear light (clamped to [0, 1]) to display-encoded.
float srgbToLinear(float encoded);
float linearToSrgb(float linear);

/// 8 bits per channel, 4 channels: what compare writes.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  ///< rows top to bottom, 4 bytes per pixel
};

/// `image` quantized to 8 bits, opaque.
Image toImage(const ColorImage& image);
/// `image` as floats in [0, 1], alpha dropped.
ColorImage toColorImage(const Image& image);

/// Writes a PNG atomically (a temporary name, then a rename). Throws softbake::Error naming the
/// file.
void writePng(const std::filesystem::path& path, const Image& image);
/// The PNG's bytes.
std::string encodePng(const Image& image);

}  // namespace softbake
