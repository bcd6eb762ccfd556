#pragma once
/// A sequence of parallel passes over fixed chunks in one parallel region: what conjugate
/// gradients is made of, a few dozen short passes a step, each of which needs all of the one
/// before it.
///
/// Why not one tbb::parallel_for per pass: the passes of a 5 000-particle scene last tens of
/// microseconds, and starting and joining a TBB loop costs a few (measured: 2.6 µs over the ideal
/// for 10 chunks of 11 µs on two threads), paid 27 times a step.
///
/// How: the threads that join take the chunks of the current phase, the first from the front and
/// the second from the back, so that each keeps about the same chunks, and their data in its
/// core's cache, from phase to phase (as TBB's halving split does). Whoever finishes the last chunk
/// of a phase runs between() alone, which reads the phase's results and says whether another
/// phase follows, then opens it. No thread waits for another to join: a thread waits only for
/// chunks already taken, which their threads are running, so a single thread (TBB gave the region
/// one, or the others are busy) runs every phase by itself. Waits spin, then yield.
///
/// The chunks, not the threads, fix what each pass computes, and between() combines chunk results
/// in chunk order, so the result is the same for any number of threads.

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <optional>
#include <thread>

#include "core/error.hpp"
#include "core/text.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace softbake {

class ChunkPhases {
  /// Bits of the claims word for each of a phase's front and back (see openPhase()).
  static constexpr int kChunkBits = 20;

 public:
  ChunkPhases() = default;
  // Its state lasts one run(): a copy starts afresh, so the objects that hold one stay copyable
  // and movable.
  ChunkPhases(const ChunkPhases&) {}
  ChunkPhases& operator=(const ChunkPhases&) { return *this; }

  /// Most chunks a phase may have, and most phases a run may have (the claims word's fields).
  static constexpr std::size_t kMaxChunks = (std::size_t(1) << kChunkBits) - 1;
  static constexpr std::uint64_t kMaxPhases = (std::uint64_t(1) << (64 - 2 * kChunkBits)) - 1;

  /// Runs pass(chunk) for chunk 0..chunks-1 of a phase, then between(), until between() returns
  /// false, at most kMaxPhases times. pass() and between() must not start TBB work of their own.
  /// Returns how many phases ran: each but the last ends in a barrier, the last in the region's
  /// join.
  template <class Pass, class Between>
  std::uint64_t run(std::size_t chunks, const Pass& pass, const Between& between) {
    if (chunks == 0) return 0;
    if (chunks > kMaxChunks)
      throw Error(cat(chunks, " chunks exceed the ", kMaxChunks, " a phase can count"));
    joined_.store(0, std::memory_order_relaxed);
    finished_.store(0, std::memory_order_relaxed);
    claims_.store(openPhase(0, chunks), std::memory_order_relaxed);
    stopAt_.store(kNever, std::memory_order_relaxed);
    completed_.store(0, std::memory_order_release);
    const auto work = [&] {
      const bool fromBack = joined_.fetch_add(1, std::memory_order_relaxed) % 2 == 1;
      for (std::uint64_t phase = 0; waitForPhase(phase); ++phase) {
        while (const std::optional<std::size_t> chunk = take(phase, fromBack)) {
          pass(*chunk);
          if (finished_.fetch_add(1, std::memory_order_acq_rel) + 1 < chunks) continue;
          finished_.store(0, std::memory_order_relaxed);
          if (!between() || phase + 1 == kMaxPhases)
            stopAt_.store(phase + 1, std::memory_order_relaxed);
          claims_.store(openPhase(phase + 1, chunks), std::memory_order_relaxed);
          completed_.store(phase + 1, std::memory_order_release);
        }
      }
    };
    const std::size_t threads =
        std::min<std::size_t>(chunks, std::size_t(tbb::this_task_arena::max_concurrency()));
    if (threads <= 1)
      work();
    else
      tbb::parallel_for(std::size_t(0), threads, [&](std::size_t) { work(); });
    return stopAt_.load(std::memory_order_relaxed);
  }

 private:
  static constexpr std::uint64_t kNever = ~std::uint64_t(0);
  static constexpr int kSpinsBeforeYield = 4096;
  static constexpr std::uint64_t kChunkMask = (std::uint64_t(1) << kChunkBits) - 1;

  /// The claims word of a phase before any chunk is taken: the phase, then the front and the back
  /// of its chunks not yet taken, kChunkBits each.
  static std::uint64_t openPhase(std::uint64_t phase, std::size_t chunks) {
    return phase << (2 * kChunkBits) | std::uint64_t(chunks);
  }

  /// A chunk of `phase` not yet taken, from the front or the back; none when all are taken or the
  /// phase is over.
  std::optional<std::size_t> take(std::uint64_t phase, bool fromBack) {
    std::uint64_t word = claims_.load(std::memory_order_relaxed);
    for (;;) {
      const std::uint64_t front = word >> kChunkBits & kChunkMask, back = word & kChunkMask;
      if (word >> (2 * kChunkBits) != phase || front >= back) return std::nullopt;
      const std::uint64_t taken = fromBack ? word - 1 : word + (std::uint64_t(1) << kChunkBits);
      if (claims_.compare_exchange_weak(word, taken, std::memory_order_relaxed))
        return std::size_t(fromBack ? back - 1 : front);
    }
  }

  /// Waits until every phase before `phase` is complete; false when the phases stopped before it.
  bool waitForPhase(std::uint64_t phase) const {
    for (int spins = 0; completed_.load(std::memory_order_acquire) < phase; ++spins) {
      if (spins < kSpinsBeforeYield) {
#if defined(__x86_64__)
        _mm_pause();
#endif
      } else {
        std::this_thread::yield();
      }
    }
    // completed_ is released after stopAt_ is set: a phase past the last is never completed.
    return phase < stopAt_.load(std::memory_order_relaxed);
  }

  // Each on its own cache line: waiting threads read completed_ while working ones take chunks
  // and count them.
  alignas(64) std::atomic<std::uint64_t> claims_{0};       ///< see openPhase()
  alignas(64) std::atomic<std::uint64_t> finished_{0};     ///< chunks finished of this phase
  alignas(64) std::atomic<std::uint64_t> completed_{0};    ///< phases completed, between() too
  alignas(64) std::atomic<std::uint64_t> stopAt_{kNever};  ///< the first phase that does not run
  std::atomic<std::uint64_t> joined_{0};                   ///< threads that joined this run
};

}  // namespace softbake
