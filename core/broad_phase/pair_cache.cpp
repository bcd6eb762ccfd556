#include "core/broad_phase/pair_cache.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>

namespace softbake {

namespace {
constexpr std::size_t kBoxGrain = 2048;     ///< triangles per chunk of a pass over boxes, at least
constexpr std::size_t kFilterGrain = 2048;  ///< cached pairs per filter chunk, at least
constexpr std::size_t kMostChunks = 64;     ///< chunks of the filter and the leavers' scan
}  // namespace

void PairCache::rebuild(BroadPhase& broadPhase, const BroadPhaseInput& input) {
  const std::size_t count = input.triangleBox.size();
  const bool first = margin_ < 0;
  if (first) {
    double size = 0;
    for (const Box3& box : input.triangleBox) size += double(box.sizes().maxCoeff());
    margin_ = count ? Scalar(marginFraction_ * size / double(count)) : Scalar(0);
  }
  const auto growAll = [&] {
    grown_.resize(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kBoxGrain),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t t = range.begin(); t != range.end(); ++t)
                          grown_[t] = grow(input.triangleBox[t]);
                      });
    broadPhase.findPairs(grownInput(input), cached_);
  };
  growAll();
  // A margin from the mean box is too wide where long slivers crowd (the cylinders of a CAD
  // assembly): an engine of 110k faces cached 30 times its 1.5M exact pairs, and every stage of
  // every substep filters them all. So the first rebuild narrows it until the cache holds at
  // most kMostCachedPerPair times the exact pairs; the pairs stay exact at any margin.
  while (first && margin_ > 0 &&
         cached_.size() > kMostCachedPerPair * std::max<std::size_t>(exactCount(input), 1024)) {
    margin_ /= 2;
    growAll();
  }
  flatSeen_.assign(input.patchFlat.begin(), input.patchFlat.end());
  flatWithSeen_.assign(input.patchFlatWith.begin(), input.patchFlatWith.end());
  surfaceCount_ = input.surfaces.size();
  updatedSinceRebuild_ = 0;
  ++rebuilds_;
}

std::size_t PairCache::exactCount(const BroadPhaseInput& input) const {
  const Box3* box = input.triangleBox.data();
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, cached_.size(), kFilterGrain), std::size_t(0),
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t kept) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
          kept += std::size_t(overlaps(box[cached_[i].first], box[cached_[i].second]));
        return kept;
      },
      std::plus<>());
}

Box3 PairCache::grow(const Box3& box) const {
  return Box3(box.min().array() - margin_, box.max().array() + margin_);
}

BroadPhaseInput PairCache::grownInput(const BroadPhaseInput& input) const {
  BroadPhaseInput grown = input;
  grown.triangleBox = grown_;
  return grown;
}

bool PairCache::markTurned(const BroadPhaseInput& input) {
  const std::size_t count = input.triangleBox.size();
  if (margin_ < 0 || grown_.size() != count || surfaceCount_ != input.surfaces.size() ||
      flatSeen_.size() != input.patchFlat.size() ||
      flatWithSeen_.size() != input.patchFlatWith.size())
    return false;
  anyTurned_ = false;
  turned_.resize(flatSeen_.size());
  for (std::size_t p = 0; p < turned_.size(); ++p) {
    bool turned = flatSeen_[p] != input.patchFlat[p];
    // A pair of neighbours turned flat as one, or back: the entries of both patches agree.
    if (!flatWithSeen_.empty())
      for (Index k = input.patchNeighbourStart[p]; k < input.patchNeighbourStart[p + 1]; ++k)
        turned = turned || flatWithSeen_[k] != input.patchFlatWith[k];
    turned_[p] = std::uint8_t(turned);
    anyTurned_ = anyTurned_ || turned;
  }
  return true;
}

std::size_t PairCache::scanChunks(std::size_t count) {
  return std::min(kMostChunks, (count + kBoxGrain - 1) / kBoxGrain);
}

void PairCache::scanChunk(const BroadPhaseInput& input, std::size_t chunk, std::size_t chunks) {
  const std::size_t count = input.triangleBox.size();
  std::vector<Index>& out = leftChunks_[chunk];
  for (std::size_t t = count * chunk / chunks; t < count * (chunk + 1) / chunks; ++t) {
    // Without patches turned, trianglePatch is not read: an input may have none.
    const auto turned = [&] {
      const Index patch = input.trianglePatch[t];
      return patch < turned_.size() && turned_[patch];
    };
    if (!grown_[t].contains(input.triangleBox[t]) || (anyTurned_ && turned()))
      out.push_back(Index(t));
  }
}

std::size_t PairCache::filterChunks() const {
  return std::min(kMostChunks, (cached_.size() + kFilterGrain - 1) / kFilterGrain);
}

void PairCache::filterChunk(const BroadPhaseInput& input, std::span<const std::uint8_t> involving,
                            std::size_t chunk, std::size_t chunks) {
  // Without branches: a quarter of the cached pairs overlap, in no pattern a branch predictor
  // learns, so each pair is written and kept or overwritten by the next.
  const Box3* box = input.triangleBox.data();
  std::vector<TrianglePair>& out = buffers_[chunk];
  const std::size_t begin = cached_.size() * chunk / chunks;
  const std::size_t end = cached_.size() * (chunk + 1) / chunks;
  out.resize(end - begin);
  std::size_t kept = 0;
  if (involving.empty()) {
    for (std::size_t i = begin; i < end; ++i) {
      const TrianglePair pair = cached_[i];
      out[kept] = pair;
      kept += unsigned(overlaps(box[pair.first], box[pair.second]));
    }
  } else {
    // Few triangles are flagged: their flags, a byte each, are read first and stay in cache.
    for (std::size_t i = begin; i < end; ++i) {
      const TrianglePair pair = cached_[i];
      if (!(involving[pair.first] | involving[pair.second])) continue;
      out[kept] = pair;
      kept += unsigned(overlaps(box[pair.first], box[pair.second]));
    }
  }
  out.resize(kept);
}

bool PairCache::update(BroadPhase& broadPhase, const BroadPhaseInput& input) {
  const std::size_t count = input.triangleBox.size();
  // The triangles that left, found in chunks by filterIfStill() and joined in chunk order:
  // ascending.
  leftChunks_.join(left_);
  if (left_.empty()) return true;
  // Triangles found again one by one cost more than in a rebuild, which also recentres every
  // grown box: once those found since the latest rebuild add up to kRebuildShare of all, rebuild.
  updatedSinceRebuild_ += left_.size();
  if (double(updatedSinceRebuild_) > kRebuildShare * double(count)) return false;

  for (Index t : left_) grown_[t] = grow(input.triangleBox[t]);
  if (!broadPhase.findPairsInvolving(grownInput(input), left_, fresh_)) return false;
  // Their old pairs out, their new ones in, in order.
  hasLeft_.resize(count);
  for (Index t : left_) hasLeft_[t] = 1;
  cached_.erase(std::remove_if(cached_.begin(), cached_.end(),
                               [&](const TrianglePair& pair) {
                                 return hasLeft_[pair.first] | hasLeft_[pair.second];
                               }),
                cached_.end());
  for (Index t : left_) hasLeft_[t] = 0;
  merged_.resize(cached_.size() + fresh_.size());
  std::merge(cached_.begin(), cached_.end(), fresh_.begin(), fresh_.end(), merged_.begin());
  cached_.swap(merged_);
  flatSeen_.assign(input.patchFlat.begin(), input.patchFlat.end());
  flatWithSeen_.assign(input.patchFlatWith.begin(), input.patchFlatWith.end());
  ++updates_;
  return true;
}

PairCache::Still PairCache::filterIfStill(const BroadPhaseInput& input,
                                          std::vector<TrianglePair>& pairs,
                                          std::span<const std::uint8_t> involving) {
  // Most substeps no box leaves its grown box: the scan for those that left and the filter of the
  // cached pairs then run in one parallel loop, where one after the other cost a barrier more.
  if (!markTurned(input)) return Still::NotMade;
  const std::size_t scans = scanChunks(input.triangleBox.size()), filters = filterChunks();
  leftChunks_.reset(scans);
  buffers_.reset(filters);
  tbb::parallel_for(std::size_t(0), std::max(scans, filters), [&](std::size_t chunk) {
    if (chunk < scans) scanChunk(input, chunk, scans);
    if (chunk < filters) filterChunk(input, involving, chunk, filters);
  });
  for (std::size_t chunk = 0; chunk < scans; ++chunk)
    if (!leftChunks_[chunk].empty()) return Still::Left;
  buffers_.join(pairs);
  return Still::Filtered;
}

void PairCache::findPairs(BroadPhase& broadPhase, const BroadPhaseInput& input,
                          std::vector<TrianglePair>& pairs,
                          std::span<const std::uint8_t> involving) {
  const Still still = filterIfStill(input, pairs, involving);
  if (still == Still::Filtered) return;
  if (still == Still::NotMade || !update(broadPhase, input)) rebuild(broadPhase, input);
  filter(input, pairs, involving);
}

void PairCache::filter(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs,
                       std::span<const std::uint8_t> involving) {
  // Filtered in parallel chunks, concatenated in chunk order: the cached order, sorted, is kept.
  const std::size_t chunks = filterChunks();
  buffers_.reset(chunks);
  tbb::parallel_for(std::size_t(0), chunks,
                    [&](std::size_t chunk) { filterChunk(input, involving, chunk, chunks); });
  buffers_.join(pairs);
}

}  // namespace softbake
