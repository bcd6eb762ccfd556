// The PNG encoder (render/png_encoder.hpp) against zlib's own inflate and stb_image's decoder: the
// pixels come back, every chunk's CRC and the stream's Adler-32 hold, and a frame encoded in a
// sequence, with pieces reused from the frame before, is the same bytes as the frame on its own.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "render/png_encoder.hpp"
#include "tests/render/render_support.hpp"

namespace softbake {
namespace {

/// A frame of a sequence: a still background (a gradient with a grid, as the ground is) and a
/// disc that moves with `frame`, so most rows are the same from frame to frame and some are not.
std::vector<std::uint8_t> sequenceFrame(int width, int height, int frame) {
  std::vector<std::uint8_t> rgb(std::size_t(width) * std::size_t(height) * 3);
  const int cx = 40 + 23 * frame, cy = height / 2, radius = height / 6;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = &rgb[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3];
      const bool grid = x % 16 == 0 || y % 16 == 0;
      p[0] = std::uint8_t(grid ? 90 : 120 + y * 100 / height);
      p[1] = std::uint8_t(grid ? 90 : 130 + x * 90 / width);
      p[2] = std::uint8_t(140);
      if ((x - cx) * (x - cx) + (y - cy) * (y - cy) < radius * radius) {
        p[0] = std::uint8_t(200 + (x * 7 + y * 3) % 50);
        p[1] = std::uint8_t(60);
        p[2] = std::uint8_t((x * y) % 256);
      }
    }
  return rgb;
}

std::uint32_t bigEndian(const std::string& bytes, std::size_t at) {
  return std::uint32_t(std::uint8_t(bytes[at])) << 24 |
         std::uint32_t(std::uint8_t(bytes[at + 1])) << 16 |
         std::uint32_t(std::uint8_t(bytes[at + 2])) << 8 |
         std::uint32_t(std::uint8_t(bytes[at + 3]));
}

/// Checks the signature and every chunk's CRC with zlib's crc32, and returns the filtered rows
/// inflated by zlib, which checks the stream's Adler-32.
std::string inflateIdat(const std::string& png) {
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  EXPECT_EQ(png.substr(0, 8), signature);
  std::string idat;
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const std::uint32_t length = bigEndian(png, at);
    const std::string type = png.substr(at + 4, 4);
    const auto* typeAndData = reinterpret_cast<const Bytef*>(png.data() + at + 4);
    EXPECT_EQ(crc32(0, typeAndData, uInt(length + 4)), bigEndian(png, at + 8 + length))
        << type << " chunk's CRC";
    if (type == "IDAT") idat += png.substr(at + 8, length);
    at += 12 + length;
  }
  std::string rows(1 << 24, '\0');
  uLongf size = uLongf(rows.size());
  const int status = uncompress(reinterpret_cast<Bytef*>(rows.data()), &size,
                                reinterpret_cast<const Bytef*>(idat.data()), uLong(idat.size()));
  EXPECT_EQ(status, Z_OK) << "zlib could not inflate the image data (a bad stream or Adler-32)";
  rows.resize(status == Z_OK ? size : 0);
  return rows;
}

TEST(PngEncoder, TheImageComesBackThroughZlibAndStb) {
  const int width = 301, height = 173;  // odd sizes: rows and pieces do not line up
  const std::vector<std::uint8_t> rgb = sequenceFrame(width, height, 3);
  const std::string png = encodePng(rgb, width, height);
  const std::string rows = inflateIdat(png);
  ASSERT_EQ(rows.size(), std::size_t(height) * (std::size_t(width) * 3 + 1));
  for (int y = 0; y < height; ++y)
    ASSERT_EQ(rows[std::size_t(y) * (std::size_t(width) * 3 + 1)], 1) << "row " << y << ": Sub";
  const test::Image decoded = test::decodePng(png);
  EXPECT_EQ(decoded.width, width);
  EXPECT_EQ(decoded.height, height);
  EXPECT_EQ(decoded.rgb, rgb);
}

TEST(PngEncoder, AFrameInASequenceIsTheSameBytesAsOnItsOwn) {
  // 1280x720: 2.8 MB of rows, 43 pieces; the disc changes a third of the rows.
  PngEncoder sequence;
  int reused = 0;
  for (int frame = 0; frame < 6; ++frame) {
    const int width = frame == 3 ? 640 : 1280, height = frame == 3 ? 360 : 720;
    const std::vector<std::uint8_t> rgb = sequenceFrame(width, height, frame);
    const std::string png = sequence.encode(rgb, width, height);
    EXPECT_EQ(png, encodePng(rgb, width, height)) << "frame " << frame;
    EXPECT_EQ(test::decodePng(png).rgb, rgb) << "frame " << frame;
    EXPECT_EQ(inflateIdat(png).size(), std::size_t(height) * (std::size_t(width) * 3 + 1));
    EXPECT_GT(sequence.piecesDeflated(), 0) << "frame " << frame << ": the disc moved";
    if (frame == 0 || frame == 3 || frame == 4) {
      // The first frame, and a change of size and back: nothing to reuse.
      EXPECT_EQ(sequence.piecesReused(), 0) << "frame " << frame;
    } else {
      EXPECT_GT(sequence.piecesReused(), sequence.piecesDeflated()) << "frame " << frame;
    }
    reused += sequence.piecesReused();
  }
  EXPECT_GT(reused, 0);

  // The same frame again: every piece reused, the same bytes.
  const std::vector<std::uint8_t> last = sequenceFrame(1280, 720, 5);
  EXPECT_EQ(sequence.encode(last, 1280, 720), encodePng(last, 1280, 720));
  EXPECT_EQ(sequence.piecesDeflated(), 0);
}

TEST(PngEncoder, AnImageOfTheWrongSizeIsRefused) {
  PngEncoder encoder;
  EXPECT_THROW(encoder.encode(std::vector<std::uint8_t>(10, 0), 4, 4), Error);
  EXPECT_THROW(encoder.encode({}, 0, 0), Error);
}

}  // namespace
}  // namespace softbake
