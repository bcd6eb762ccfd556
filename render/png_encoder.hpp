#pragma once
/// PNG file bytes of rendered frames. Most of a frame in a sequence is the ground drawn once, the
/// same pixels as in the frame before, and deflating them again was the largest cost of writing
/// a frame after the rendering itself. The encoder deflates the filtered image in pieces of
/// fixed size, each on its own (a reset compressor, flushed to a byte boundary), so a piece's
/// deflated bytes depend on that piece alone: a piece equal to the previous frame's is not
/// deflated again. The file is the same bytes whether a piece was reused or not, so a frame
/// encodes the same in a sequence as on its own.
///
/// The filtering and the chunks are stb_image_write's; each row is filtered with PNG's Sub
/// filter, which on these images is within 3% of the size of stb's per-row choice among all five
/// at half its cost.

#include <cstdint>
#include <string>
#include <vector>

namespace softbake {

class PngEncoder {
 public:
  /// PNG bytes of an RGB8 image, top row first. Throws softbake::Error when encoding fails.
  std::string encode(const std::vector<std::uint8_t>& rgb, int width, int height);

  /// Of the last encode(): pieces deflated, and pieces reused from the frame before.
  int piecesDeflated() const { return deflated_; }
  int piecesReused() const { return reused_; }

  /// Called by stb_image_write with the filtered image: a zlib stream, malloc'ed. Public only for
  /// that callback.
  unsigned char* deflate(const unsigned char* data, int length, int* outLength);

 private:
  struct Piece {
    std::string deflated;  ///< raw deflate, ends on a byte boundary, not final
    unsigned long adler = 1;
  };
  std::vector<unsigned char> previous_;  ///< the last filtered image
  std::vector<Piece> pieces_;            ///< its pieces
  int deflated_ = 0, reused_ = 0;
};

/// PNG bytes of an RGB8 image, top row first, on its own: the bytes PngEncoder writes for it.
std::string encodePng(const std::vector<std::uint8_t>& rgb, int width, int height);

}  // namespace softbake
