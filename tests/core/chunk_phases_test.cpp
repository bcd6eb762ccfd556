// ChunkPhases (core/dynamics/chunk_phases.hpp), the implicit solve's phases in one parallel
// region: every chunk of every phase runs once, a phase sees all that the one before it wrote,
// between() runs alone, and run() returns the phases that ran, the barriers
// bench/regions_per_step.sh counts. Checked on 1 to 4 threads against counts made by hand.
#include "core/dynamics/chunk_phases.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <atomic>
#include <cstdint>
#include <vector>

#include "core/error.hpp"

namespace softbake {
namespace {

TEST(ChunkPhases, EachPhaseRunsEveryChunkOnceAndSeesThePhaseBefore) {
  for (const int threads : {1, 2, 3, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    for (const std::size_t chunks : {std::size_t(1), std::size_t(3), std::size_t(64)}) {
      constexpr int kPhases = 9;
      ChunkPhases phases;
      // Each chunk writes its phase into its own slot, and reads every other chunk's slot, which
      // the phase before must have left there: a missing barrier reads a stale or a later phase.
      std::vector<std::atomic<int>> written(chunks);
      for (auto& slot : written) slot.store(-1);
      std::vector<std::atomic<int>> runs(kPhases * chunks);
      for (auto& count : runs) count.store(0);
      std::atomic<int> stale{0}, concurrentBetween{0}, inBetween{0};
      int phase = 0;
      std::vector<int> chunksSeenByBetween;
      const std::uint64_t ran = phases.run(
          chunks,
          [&](std::size_t chunk) {
            for (std::size_t other = 0; other < chunks; ++other) {
              const int seen = written[other].load(std::memory_order_relaxed);
              // Another chunk of this phase may have written already; none may be behind.
              if (seen != phase - 1 && seen != phase) ++stale;
            }
            runs[std::size_t(phase) * chunks + chunk].fetch_add(1);
            written[chunk].store(phase, std::memory_order_relaxed);
          },
          [&] {
            if (inBetween.fetch_add(1) != 0) ++concurrentBetween;
            int done = 0;
            for (std::size_t chunk = 0; chunk < chunks; ++chunk)
              done += runs[std::size_t(phase) * chunks + chunk].load();
            chunksSeenByBetween.push_back(done);
            ++phase;
            inBetween.fetch_sub(1);
            return phase < kPhases;
          });
      EXPECT_EQ(ran, std::uint64_t(kPhases)) << threads << " threads, " << chunks << " chunks";
      EXPECT_EQ(phase, kPhases);
      EXPECT_EQ(stale.load(), 0);
      EXPECT_EQ(concurrentBetween.load(), 0);
      for (std::size_t k = 0; k < runs.size(); ++k) EXPECT_EQ(runs[k].load(), 1) << "run " << k;
      for (const int done : chunksSeenByBetween) EXPECT_EQ(done, int(chunks));
    }
  }
}

TEST(ChunkPhases, NoChunksRunNothingAndTooManyAreRefused) {
  ChunkPhases phases;
  int calls = 0;
  EXPECT_EQ(phases.run(
                0, [&](std::size_t) { ++calls; }, [&] { return ++calls < 3; }),
            0u);
  EXPECT_EQ(calls, 0);
  EXPECT_THROW(phases.run(
                   ChunkPhases::kMaxChunks + 1, [](std::size_t) {}, [] { return false; }),
               Error);
}

TEST(ChunkPhases, ARegionRunAgainStartsAfresh) {
  // The solve runs one region after another with the same object (an active-set round solves
  // again): each run counts its own phases from the first.
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
  ChunkPhases phases;
  for (const int wanted : {5, 1, 12}) {
    int phase = 0;
    std::atomic<int> chunksRun{0};
    const std::uint64_t ran = phases.run(
        4, [&](std::size_t) { chunksRun.fetch_add(1); }, [&] { return ++phase < wanted; });
    EXPECT_EQ(ran, std::uint64_t(wanted));
    EXPECT_EQ(chunksRun.load(), 4 * wanted);
  }
}

}  // namespace
}  // namespace softbake
