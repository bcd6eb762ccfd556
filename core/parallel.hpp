#pragma once
/// What every parallel loop of the core shares: how much work a task takes, and per-chunk
/// output buffers joined in chunk order, so that what a loop finds comes out in the same order
/// for any number of threads.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace softbake {

/// Particles per task: a 5 000-particle scene still splits over two threads, and a task is long
/// enough that TBB's scheduling does not show.
inline constexpr std::size_t kParticleGrain = 2048;
/// Triangles per task, for loops that do as little per triangle as the particle loops per
/// particle (a box, a normal, a volume term).
inline constexpr std::size_t kTriangleGrain = 4096;

/// One output buffer per chunk of a parallel loop over a fixed split of the work: each chunk
/// writes only its own, and join() appends them in chunk order. Buffers keep their capacity, so
/// a loop run again on work of the same size allocates nothing.
template <class T>
class ChunkBuffers {
 public:
  /// `chunks` empty buffers.
  void reset(std::size_t chunks) {
    if (buffers_.size() < chunks) buffers_.resize(chunks);
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) buffers_[chunk].clear();
    chunks_ = chunks;
  }
  std::vector<T>& operator[](std::size_t chunk) { return buffers_[chunk]; }
  std::size_t chunks() const { return chunks_; }

  /// Replaces `out` with every buffer's items, in chunk order.
  void join(std::vector<T>& out) const {
    out.clear();
    for (std::size_t chunk = 0; chunk < chunks_; ++chunk)
      out.insert(out.end(), buffers_[chunk].begin(), buffers_[chunk].end());
  }

  /// Grows every buffer's capacity to the largest any has needed. Which chunk an item falls in
  /// moves with the work (resting contacts drift between chunks of pairs): sized so, the
  /// buffers settle to no allocation.
  void reserveLargest() {
    std::size_t most = 0;
    for (std::size_t chunk = 0; chunk < chunks_; ++chunk)
      most = std::max(most, buffers_[chunk].size());
    for (std::size_t chunk = 0; chunk < chunks_; ++chunk) buffers_[chunk].reserve(most);
  }

 private:
  std::vector<std::vector<T>> buffers_;
  std::size_t chunks_ = 0;
};

}  // namespace softbake
