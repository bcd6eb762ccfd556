#pragma once
/// Image regression for rendered frames: `softbake compare`. Pipelines commit golden frames and
/// compare each new render against them with a tolerance, because pixels differ slightly across
/// Mesa versions and GPUs while a real change (a moved camera, missing contacts) differs a lot.

#include <cstdint>
#include <filesystem>
#include <vector>

namespace softbake {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  ///< rows top to bottom, 4 bytes per pixel
};

/// Reads a PNG (or any format stb_image reads). Throws softbake::Error naming the file.
Image loadImage(const std::filesystem::path& path);
/// Writes a PNG atomically. Throws softbake::Error naming the file.
void writePng(const std::filesystem::path& path, const Image& image);

struct ImageDifference {
  std::size_t pixels = 0;
  std::size_t pixelsOverTolerance = 0;  ///< pixels whose largest channel difference > tolerance
  int largestDifference = 0;            ///< over all channels, 0–255
  double psnr = 0;                      ///< dB over RGB; +infinity for identical images
  double fractionOver() const { return pixels ? double(pixelsOverTolerance) / double(pixels) : 0; }
};

/// Compares two images of the same size (throws softbake::Error otherwise). Alpha is ignored:
/// frames are opaque. When `diff` is given it receives A dimmed to grey, with every pixel over the
/// tolerance in red, brighter for a larger difference, so a reviewer sees where a frame changed.
ImageDifference compareImages(const Image& a, const Image& b, int tolerance, Image* diff = nullptr);

}  // namespace softbake
