#include "core/collision/pair_cache.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>

namespace softbake {

namespace {
constexpr std::size_t kBoxGrain = 2048;
constexpr std::size_t kFilterGrain = 2048;  ///< cached pairs per filter chunk, at least
constexpr std::size_t kFilterChunks = 64;
}  // namespace

bool PairCache::stillValid(const BroadPhaseInput& input) const {
  if (margin_ < 0 || grown_.size() != input.triangleBox.size() ||
      surfaceCount_ != input.surfaces.size())
    return false;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, grown_.size(), kBoxGrain), true,
      [&](const tbb::blocked_range<std::size_t>& range, bool valid) {
        for (std::size_t t = range.begin(); valid && t != range.end(); ++t)
          valid = grown_[t].contains(input.triangleBox[t]);
        return valid;
      },
      std::logical_and<bool>());
}

void PairCache::rebuild(BroadPhase& broadPhase, const BroadPhaseInput& input) {
  const std::size_t count = input.triangleBox.size();
  if (margin_ < 0) {
    double size = 0;
    for (const Box3& box : input.triangleBox) size += double(box.sizes().maxCoeff());
    margin_ = count ? Scalar(marginFraction_ * size / double(count)) : Scalar(0);
  }
  grown_.resize(count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kBoxGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t)
                        grown_[t] = Box3(input.triangleBox[t].min().array() - margin_,
                                         input.triangleBox[t].max().array() + margin_);
                    });
  BroadPhaseInput grownInput = input;
  grownInput.triangleBox = grown_;
  broadPhase.findPairs(grownInput, cached_);
  surfaceCount_ = input.surfaces.size();
  ++rebuilds_;
}

void PairCache::findPairs(BroadPhase& broadPhase, const BroadPhaseInput& input,
                          std::vector<TrianglePair>& pairs) {
  if (!stillValid(input)) rebuild(broadPhase, input);
  filter(input, pairs);
}

bool PairCache::findCachedPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) {
  if (!stillValid(input)) return false;
  filter(input, pairs);
  return true;
}

void PairCache::filter(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) {
  // Filtered in parallel chunks, concatenated in chunk order: the cached order, sorted, is kept.
  // Without branches: a quarter of the cached pairs overlap, in no pattern a branch predictor
  // learns, so each pair is written and kept or overwritten by the next.
  const std::size_t chunks =
      std::min(kFilterChunks, (cached_.size() + kFilterGrain - 1) / kFilterGrain);
  buffers_.reset(chunks);
  const Box3* box = input.triangleBox.data();
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<TrianglePair>& out = buffers_[chunk];
    const std::size_t begin = cached_.size() * chunk / chunks;
    const std::size_t end = cached_.size() * (chunk + 1) / chunks;
    out.resize(end - begin);
    std::size_t kept = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const TrianglePair pair = cached_[i];
      out[kept] = pair;
      kept += unsigned(overlaps(box[pair.first], box[pair.second]));
    }
    out.resize(kept);
  });
  pairs.clear();
  for (std::size_t chunk = 0; chunk < chunks; ++chunk)
    pairs.insert(pairs.end(), buffers_[chunk].begin(), buffers_[chunk].end());
}

}  // namespace softbake
