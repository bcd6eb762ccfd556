#include "cli/image_compare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

// Static, so these copies never clash with the renderer's own stb implementation in one binary.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace softbake {

Image loadImage(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw Error(cat(path.string(), ": no such image file"));
  int width = 0, height = 0, channels = 0;
  stbi_uc* pixels = stbi_load(path.c_str(), &width, &height, &channels, 4);
  if (!pixels)
    throw Error(cat(path.string(), ": cannot read the image (", stbi_failure_reason(), ")"));
  Image image{width, height,
              std::vector<std::uint8_t>(pixels, pixels + std::size_t(width) * height * 4)};
  stbi_image_free(pixels);
  return image;
}

void writePng(const std::filesystem::path& path, const Image& image) {
  std::string bytes;
  const auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), std::size_t(size));
  };
  if (!stbi_write_png_to_func(append, &bytes, image.width, image.height, 4, image.rgba.data(),
                              image.width * 4))
    throw Error(cat(path.string(), ": cannot encode the PNG"));
  writeFileAtomically(path, bytes);
}

ImageDifference compareImages(const Image& a, const Image& b, int tolerance, Image* diff) {
  if (a.width != b.width || a.height != b.height)
    throw Error(cat("the images differ in size: ", a.width, "x", a.height, " and ", b.width, "x",
                    b.height));
  ImageDifference result;
  result.pixels = std::size_t(a.width) * std::size_t(a.height);
  if (diff) *diff = {a.width, a.height, std::vector<std::uint8_t>(a.rgba.size())};
  double squaredError = 0;
  for (std::size_t p = 0; p < result.pixels; ++p) {
    const std::uint8_t* x = &a.rgba[4 * p];
    const std::uint8_t* y = &b.rgba[4 * p];
    int largest = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(int(x[c]) - int(y[c]));
      largest = std::max(largest, d);
      squaredError += double(d) * d;
    }
    result.largestDifference = std::max(result.largestDifference, largest);
    const bool over = largest > tolerance;
    result.pixelsOverTolerance += over;
    if (diff) {
      std::uint8_t* out = &diff->rgba[4 * p];
      const auto grey = std::uint8_t((int(x[0]) + int(x[1]) + int(x[2])) / 10);  // A at 30%
      if (over) {
        out[0] = std::uint8_t(std::min(255, 128 + largest));
        out[1] = out[2] = 0;
      } else {
        out[0] = out[1] = out[2] = grey;
      }
      out[3] = 255;
    }
  }
  const double meanSquared = squaredError / (3.0 * double(std::max<std::size_t>(result.pixels, 1)));
  result.psnr = meanSquared == 0 ? std::numeric_limits<double>::infinity()
                                 : 10 * std::log10(255.0 * 255.0 / meanSquared);
  return result;
}

}  // namespace softbake
