#include "core/broad_phase/broad_phase.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cstdint>

#include "core/broad_phase/bvh.hpp"
#include "core/broad_phase/sbhash.hpp"
#include "core/broad_phase/spatial_hash.hpp"

namespace softbake {

bool pairEligible(const BroadPhaseInput& input, Index i, Index j) {
  const Index si = input.triangleSurface[i], sj = input.triangleSurface[j];
  if (si != sj) return input.surfaces[si].moving || input.surfaces[sj].moving;
  if (!input.surfaces[si].selfCollision || input.inFlatPatches(i, j)) return false;
  // Triangles sharing a vertex always touch at it: that contact is the mesh itself, not a
  // collision, so it never reaches the narrow phase.
  for (Index a : input.triangleVertices[i])
    for (Index b : input.triangleVertices[j])
      if (a == b) return false;
  return true;
}

namespace broad_phase_detail {

namespace {

/// Pairs from one buffer's bucket on: the least that makes the bucketed sort worth its passes.
constexpr std::size_t kBucketedSortMin = 16384;
/// Buckets by the high bits of `first`: enough to keep any thread count busy.
constexpr std::size_t kSortBuckets = 64;

/// Sorts `data[0, n)` and drops repeats, `temp` of the same size as the other half; returns how
/// many are left, in `data`. Key: first · 2³² + second. Bytes that are zero in every key are
/// skipped: a pass over them would keep the order.
std::size_t radixSortUnique(TrianglePair* data, TrianglePair* temp, std::size_t n) {
  std::uint32_t usedBits[2] = {0, 0};
  for (std::size_t k = 0; k < n; ++k) usedBits[0] |= data[k].second, usedBits[1] |= data[k].first;
  TrianglePair* from = data;
  TrianglePair* to = temp;
  for (int pass = 0; pass < 8; ++pass) {
    const int half = pass / 4, shift = 8 * (pass % 4);
    if (((usedBits[half] >> shift) & 0xff) == 0) continue;
    const auto digit = [&](const TrianglePair& pair) {
      return ((half ? pair.first : pair.second) >> shift) & 0xff;
    };
    std::array<std::size_t, 257> start{};
    for (std::size_t k = 0; k < n; ++k) ++start[digit(from[k]) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (std::size_t k = 0; k < n; ++k) to[start[digit(from[k])]++] = from[k];
    std::swap(from, to);
  }
  if (from != data) std::copy(from, from + n, data);
  return std::size_t(std::unique(data, data + n) - data);
}

}  // namespace

void sortUnique(std::vector<TrianglePair>& pairs, std::vector<TrianglePair>& scratch) {
  scratch.resize(pairs.size());
  pairs.resize(radixSortUnique(pairs.data(), scratch.data(), pairs.size()));
}

void PairBuffers::mergeInto(std::vector<TrianglePair>& pairs) {
  const std::size_t buffers = buffers_.chunks();
  std::size_t total = 0;
  for (std::size_t b = 0; b < buffers; ++b) total += buffers_[b].size();
  if (total < kBucketedSortMin) {
    buffers_.join(pairs);
    sortUnique(pairs, scratch_);
    return;
  }
  // Many pairs (a rebuild at a million faces): spread into buckets by the high bits of `first`,
  // so each bucket's pairs all precede the next's, and sort the buckets in parallel. The result
  // is the one sorted list, whatever the thread count.
  const Index highest = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, buffers), Index(0),
      [&](const tbb::blocked_range<std::size_t>& range, Index most) {
        for (std::size_t b = range.begin(); b != range.end(); ++b)
          for (const TrianglePair& pair : buffers_[b]) most = std::max(most, pair.first);
        return most;
      },
      [](Index a, Index b) { return std::max(a, b); });
  int shift = 0;
  while ((std::size_t(highest) >> shift) >= kSortBuckets) ++shift;
  bucketStart_.assign(buffers * kSortBuckets, 0);  // per buffer, then per bucket: its count
  tbb::parallel_for(std::size_t(0), buffers, [&](std::size_t b) {
    for (const TrianglePair& pair : buffers_[b])
      ++bucketStart_[b * kSortBuckets + (pair.first >> shift)];
  });
  // Where each buffer's part of each bucket begins: bucket by bucket, buffers in order.
  std::size_t at = 0;
  bucketEnd_.resize(kSortBuckets);
  for (std::size_t bucket = 0; bucket < kSortBuckets; ++bucket) {
    for (std::size_t b = 0; b < buffers; ++b) {
      const std::size_t count = bucketStart_[b * kSortBuckets + bucket];
      bucketStart_[b * kSortBuckets + bucket] = at;
      at += count;
    }
    bucketEnd_[bucket] = at;
  }
  scratch_.resize(total);
  pairs.resize(total);
  tbb::parallel_for(std::size_t(0), buffers, [&](std::size_t b) {
    std::size_t* next = &bucketStart_[b * kSortBuckets];
    for (const TrianglePair& pair : buffers_[b]) scratch_[next[pair.first >> shift]++] = pair;
  });
  // Each bucket sorted in place, `pairs` as its other half; then the unique ones packed.
  bucketKept_.resize(kSortBuckets);
  tbb::parallel_for(std::size_t(0), kSortBuckets, [&](std::size_t bucket) {
    const std::size_t begin = bucket ? bucketEnd_[bucket - 1] : 0;
    bucketKept_[bucket] =
        radixSortUnique(&scratch_[begin], &pairs[begin], bucketEnd_[bucket] - begin);
  });
  bucketPacked_.resize(kSortBuckets + 1);
  bucketPacked_[0] = 0;
  for (std::size_t bucket = 0; bucket < kSortBuckets; ++bucket)
    bucketPacked_[bucket + 1] = bucketPacked_[bucket] + bucketKept_[bucket];
  tbb::parallel_for(std::size_t(0), kSortBuckets, [&](std::size_t bucket) {
    const TrianglePair* from = &scratch_[bucket ? bucketEnd_[bucket - 1] : 0];
    std::copy(from, from + bucketKept_[bucket], pairs.data() + bucketPacked_[bucket]);
  });
  pairs.resize(bucketPacked_[kSortBuckets]);
}

}  // namespace broad_phase_detail

namespace {

/// Triangles per task: each row of the triangle matrix costs up to n box tests, so rows are cheap
/// to balance in small groups.
constexpr Index kBruteRowGrain = 64;

/// Every pair i < j, skipping whole surface pairs the eligibility rule rejects. The reference the
/// other broad phases are tested against, so it is written to be obviously right, not fast.
class BruteForceBroadPhase final : public BroadPhase {
 public:
  void findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) override {
    const Index triangleCount = Index(input.triangleBox.size());
    const std::size_t chunks = (triangleCount + kBruteRowGrain - 1) / kBruteRowGrain;
    buffers_.reset(chunks);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
      std::vector<TrianglePair>& out = buffers_[chunk];
      const Index rowEnd = std::min<Index>(triangleCount, Index(chunk + 1) * kBruteRowGrain);
      for (Index i = Index(chunk) * kBruteRowGrain; i < rowEnd; ++i) {
        const Index s = input.triangleSurface[i];
        for (Index t = s; t < input.surfaces.size(); ++t) {
          const CollisionSurface& other = input.surfaces[t];
          if (t == s && !other.selfCollision) continue;
          if (t != s && !input.surfaces[s].moving && !other.moving) continue;  // both static
          const Index end = other.firstTriangle + other.triangleCount;
          for (Index j = t == s ? i + 1 : other.firstTriangle; j < end; ++j)
            broad_phase_detail::addIfCandidate(input, i, j, out);
        }
      }
    });
    buffers_.mergeInto(pairs);
  }

  BroadPhaseKind kind() const override { return BroadPhaseKind::BruteForce; }

 private:
  broad_phase_detail::PairBuffers buffers_;
};

}  // namespace

std::unique_ptr<BroadPhase> makeBroadPhase(BroadPhaseKind kind, const BroadPhaseOptions& options) {
  switch (kind) {
    case BroadPhaseKind::Sbhash:
      return std::make_unique<SbhashBroadPhase>(options.subdivisionLevels);
    case BroadPhaseKind::SpatialHash:
      return std::make_unique<SpatialHashBroadPhase>();
    case BroadPhaseKind::Bvh:
      return std::make_unique<BvhBroadPhase>();
    case BroadPhaseKind::BruteForce:
      return std::make_unique<BruteForceBroadPhase>();
  }
  return nullptr;
}

}  // namespace softbake
