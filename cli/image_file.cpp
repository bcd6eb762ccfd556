#include "cli/image_file.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

// Static, so this copy never clashes with the renderer's own stb implementation in one binary.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace softbake {

namespace {

/// Whether the file holds linear light, not display-encoded values: what OpenImageIO says of its
/// colour space, or, where it says nothing, a float format (EXR, float TIFF).
bool isLinear(const OIIO::ImageSpec& spec) {
  std::string space = spec.get_string_attribute("oiio:ColorSpace");
  std::transform(space.begin(), space.end(), space.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (space.find("srgb") != std::string::npos && space.find("lin") == std::string::npos)
    return false;
  if (space.find("lin") != std::string::npos) return true;
  return spec.format.is_floating_point();
}

/// Whether a PNG file ends as every whole one does, with its IEND chunk. libpng reports a file cut
/// short only while decoding it, through a path that leaks inside OpenImageIO 2.4 (a message
/// string skipped by its longjmp), so a truncated frame is refused before that.
bool pngEndsWhole(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  const std::streamoff size = file.tellg();
  if (size < 12) return false;
  const std::streamoff tail = std::min<std::streamoff>(size, 64);
  std::string end(std::size_t(tail), '\0');
  file.seekg(size - tail);
  file.read(end.data(), tail);
  return end.find(std::string("IEND\xAE\x42\x60\x82", 8)) != std::string::npos;
}

}  // namespace

float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1 / 2.4f) - 0.055f;
}

ColorImage readImage(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw Error(cat(path.string(), ": no such image file"));
  auto input = OIIO::ImageInput::open(path.string());
  if (!input) throw Error(cat(path.string(), ": cannot read the image (", OIIO::geterror(), ")"));
  if (std::string_view(input->format_name()) == "png" && !pngEndsWhole(path))
    throw Error(cat(path.string(),
                    ": cannot read the image (the PNG is cut short: it does not end "
                    "with its IEND chunk)"));
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
    throw Error(cat(path.string(), ": not a flat 2D image (", spec.width, "x", spec.height, "x",
                    spec.depth, ", ", spec.nchannels, " channels)"));
  const int channels = spec.nchannels;
  std::vector<float> values(std::size_t(spec.width) * std::size_t(spec.height) *
                            std::size_t(channels));
  if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, values.data())) {
    std::string reason = input->geterror();
    if (reason.empty()) reason = OIIO::geterror();
    throw Error(cat(path.string(), ": cannot read the image (",
                    reason.empty() ? "its data is damaged or cut short" : reason, ")"));
  }
  const bool linear = isLinear(spec);
  ColorImage image{spec.width, spec.height, {}};
  image.rgb.resize(3 * image.pixels());
  for (std::size_t p = 0; p < image.pixels(); ++p)
    for (int c = 0; c < 3; ++c) {
      // Grey (with or without alpha) spreads to RGB; alpha and channels past blue are dropped.
      const int source = channels < 3 ? 0 : c;
      const float v = values[p * std::size_t(channels) + std::size_t(source)];
      image.rgb[3 * p + std::size_t(c)] = linear ? linearToSrgb(v) : std::clamp(v, 0.0f, 1.0f);
    }
  return image;
}

Image toImage(const ColorImage& image) {
  Image out{image.width, image.height, std::vector<std::uint8_t>(4 * image.pixels(), 255)};
  for (std::size_t p = 0; p < image.pixels(); ++p)
    for (std::size_t c = 0; c < 3; ++c)
      out.rgba[4 * p + c] = std::uint8_t(std::lround(255 * image.rgb[3 * p + c]));
  return out;
}

ColorImage toColorImage(const Image& image) {
  ColorImage out{image.width, image.height, {}};
  out.rgb.resize(3 * out.pixels());
  for (std::size_t p = 0; p < out.pixels(); ++p)
    for (std::size_t c = 0; c < 3; ++c) out.rgb[3 * p + c] = image.rgba[4 * p + c] / 255.0f;
  return out;
}

std::string encodePng(const Image& image) {
  std::string bytes;
  const auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), std::size_t(size));
  };
  if (!stbi_write_png_to_func(append, &bytes, image.width, image.height, 4, image.rgba.data(),
                              image.width * 4))
    throw Error(cat("cannot encode a ", image.width, "x", image.height, " PNG"));
  return bytes;
}

void writePng(const std::filesystem::path& path, const Image& image) {
  writeFileAtomically(path, encodePng(image));
}

}  // namespace softbake
