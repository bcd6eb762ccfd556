#include "render/png_encoder.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {
namespace {
/// The encoder stb_image_write's compression callback works for; the callback has no context.
thread_local PngEncoder* tEncoder = nullptr;

/// stb is C: an exception must not pass through it (it would leak its buffers); a null stream
/// makes it fail, and encode() reports that.
unsigned char* deflateForStb(unsigned char* data, int length, int* outLength, int /*quality*/) {
  try {
    return tEncoder ? tEncoder->deflate(data, length, outLength) : nullptr;
  } catch (...) {
    return nullptr;
  }
}
}  // namespace
}  // namespace softbake

#define STBIW_ZLIB_COMPRESS softbake::deflateForStb
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace softbake {
namespace {

/// 64 KiB of filtered rows, 17 rows of a 1280-pixel image: small enough that a frame's changed
/// rows leave most pieces as they were, large enough that a reset dictionary every piece costs
/// under 1% of the file.
constexpr std::size_t kPieceBytes = std::size_t(1) << 16;

/// Sub on every row: set once, before any thread encodes (stb reads it while filtering).
[[maybe_unused]] const bool kSubFilter = [] {
  stbi_write_force_png_filter = 1;
  return true;
}();

/// Raw deflate of one piece at zlib's fastest level, from a fresh dictionary, flushed to a byte
/// boundary so the pieces concatenate into one stream.
std::string deflatePiece(z_stream& stream, const unsigned char* data, std::size_t size) {
  if (deflateReset(&stream) != Z_OK) throw Error("PNG: zlib could not reset its compressor");
  std::string out(deflateBound(&stream, uLong(size)) + 16, '\0');
  stream.next_in = const_cast<unsigned char*>(data);
  stream.avail_in = uInt(size);
  stream.next_out = reinterpret_cast<unsigned char*>(out.data());
  stream.avail_out = uInt(out.size());
  if (::deflate(&stream, Z_SYNC_FLUSH) != Z_OK || stream.avail_in != 0)
    throw Error("PNG: zlib could not deflate a piece of the image");
  out.resize(out.size() - stream.avail_out);
  return out;
}

}  // namespace

unsigned char* PngEncoder::deflate(const unsigned char* data, int length, int* outLength) {
  const std::size_t size = std::size_t(length);
  const std::size_t count = (size + kPieceBytes - 1) / kPieceBytes;
  const bool sameShape = previous_.size() == size;
  if (!sameShape) {
    previous_.assign(data, data + size);
    pieces_.assign(count, Piece{});
  }
  z_stream stream{};
  if (deflateInit2(&stream, Z_BEST_SPEED, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw Error("PNG: zlib could not start a compressor");
  deflated_ = reused_ = 0;
  std::size_t total = 2 + 2 + 4;  // zlib header, the final empty block, Adler-32
  try {
    for (std::size_t p = 0; p < count; ++p) {
      const std::size_t begin = p * kPieceBytes, bytes = std::min(kPieceBytes, size - begin);
      Piece& piece = pieces_[p];
      if (sameShape && !piece.deflated.empty() &&
          std::memcmp(data + begin, previous_.data() + begin, bytes) == 0) {
        ++reused_;
      } else {
        std::memcpy(previous_.data() + begin, data + begin, bytes);
        piece.deflated = deflatePiece(stream, data + begin, bytes);
        piece.adler = adler32(1, data + begin, uInt(bytes));
        ++deflated_;
      }
      total += piece.deflated.size();
    }
  } catch (...) {
    deflateEnd(&stream);
    throw;
  }
  deflateEnd(&stream);

  // stb frees the stream with free().
  auto* out = static_cast<unsigned char*>(std::malloc(total));
  if (!out) return nullptr;
  unsigned char* o = out;
  *o++ = 0x78;  // deflate, 32 KiB window
  *o++ = 0x01;  // fastest level; 0x7801 is a multiple of 31, as the header check requires
  uLong adler = adler32(0, nullptr, 0);
  for (std::size_t p = 0; p < count; ++p) {
    o = std::copy(pieces_[p].deflated.begin(), pieces_[p].deflated.end(), o);
    const std::size_t bytes = std::min(kPieceBytes, size - p * kPieceBytes);
    adler = adler32_combine(adler, pieces_[p].adler, z_off_t(bytes));
  }
  // An empty final block with fixed codes: BFINAL 1, BTYPE 01, end-of-block code 0000000.
  *o++ = 0x03;
  *o++ = 0x00;
  for (int shift = 24; shift >= 0; shift -= 8) *o++ = static_cast<unsigned char>(adler >> shift);
  *outLength = int(total);
  return out;
}

std::string PngEncoder::encode(const std::vector<std::uint8_t>& rgb, int width, int height) {
  if (width < 1 || height < 1 || rgb.size() != std::size_t(width) * std::size_t(height) * 3)
    throw Error(cat("PNG: ", rgb.size(), " bytes are not a ", width, "x", height, " RGB image"));
  std::string png;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), std::size_t(size));
  };
  tEncoder = this;
  const int written = stbi_write_png_to_func(append, &png, width, height, 3, rgb.data(), width * 3);
  tEncoder = nullptr;
  if (!written) {
    previous_.clear();  // a piece may have been left half made
    throw Error(cat("PNG: encoding a ", width, "x", height, " image failed"));
  }
  return png;
}

std::string encodePng(const std::vector<std::uint8_t>& rgb, int width, int height) {
  PngEncoder encoder;
  return encoder.encode(rgb, width, height);
}

}  // namespace softbake
