#pragma once
/// Temporal coherence for any broad phase ("Verlet lists", fat boxes): the broad phase runs on
/// every triangle's box grown by a margin, and while each triangle's current box stays inside its
/// grown one, the exact pairs of a step are the cached pairs whose current boxes overlap.
///
/// Why that is exact: a pair whose current boxes overlap has overlapping grown boxes (each current
/// box lies inside its grown box), so the broad phase listed it; eligibility is topology and never
/// changes. Filtering the sorted cached list keeps it sorted. So the pairs are exactly, and in the
/// same order, what the broad phase would return on the current boxes: results stay identical,
/// byte for byte, with the cache on or off. A substep moves a particle by a tiny fraction of a
/// triangle, so the broad phase runs once every few dozen steps instead of every step.
///
/// When some triangles leave their grown boxes, the whole cache need not be rebuilt: those
/// triangles get boxes grown around where they are now, their cached pairs are dropped, and the
/// broad phase lists their pairs alone (findPairsInvolving), which are merged into the sorted
/// list. Every other pair's two grown boxes are unchanged, so the cache still holds every eligible
/// pair whose grown boxes overlap, and stays exact. It matters at a million triangles, where some
/// triangle leaves its grown box on every step, so a cache rebuilt whole was rebuilt every step.
/// Once the triangles found again alone add up to kRebuildShare of them all, or the broad phase
/// cannot answer for a few, the cache is rebuilt whole.

#include <cstdint>
#include <span>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/parallel.hpp"

namespace softbake {

class PairCache {
 public:
  /// `margin`: how far, as a fraction of the mean triangle box size at the first step, each box
  /// is grown. Larger: fewer rebuilds, more cached pairs to filter.
  explicit PairCache(double margin = 0.25) : marginFraction_(margin) {}

  /// The exact overlapping eligible pairs of `input`, sorted, using `broadPhase` only when some
  /// box has left its grown box (or on the first call, or when the surfaces changed). Any boxes
  /// of the same triangles will do: a later stage of the substep (the failsafe) shares the cache.
  /// With `involving` (a flag per triangle), only the pairs with a flagged triangle: a later pass
  /// of the failsafe measures again only what its previous pass moved.
  void findPairs(BroadPhase& broadPhase, const BroadPhaseInput& input,
                 std::vector<TrianglePair>& pairs, std::span<const std::uint8_t> involving = {});

  std::size_t rebuilds() const { return rebuilds_; }
  /// Pairs the cache holds: the overlapping pairs of the grown boxes.
  std::size_t cachedPairs() const { return cached_.size(); }
  /// Steps on which some triangles left their grown boxes and only their pairs were found again.
  std::size_t updates() const { return updates_; }

  /// Finding the pairs of triangles one by one costs more per triangle than a rebuild, which
  /// descends two trees together and recentres every grown box. Once the triangles found again
  /// one by one since the latest rebuild add up to this fraction of them all, the cache is rebuilt
  /// instead. Measured on figure 7 and balls1m (bench/results/integrators.md).
  static constexpr double kRebuildShare = 0.25;
  /// The first rebuild halves the margin until the cache holds at most this many times the exact
  /// pairs. Figure 7, the piles and balls100k hold 2.6 to 3.4 times at the default margin and keep
  /// it. An engine of 110k faces, whose failsafe filters the cache 10 to 25 times a substep,
  /// baked a frame 14% faster at 4 than at 8, and 19% at 2, where balls100k was 13% slower
  /// (bench/results/assemblies.md).
  static constexpr std::size_t kMostCachedPerPair = 4;

 private:
  void filter(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs,
              std::span<const std::uint8_t> involving);
  void rebuild(BroadPhase& broadPhase, const BroadPhaseInput& input);
  /// How many cached pairs overlap in `input`: what filter() would keep.
  std::size_t exactCount(const BroadPhaseInput& input) const;
  /// The cache made valid for `input` by finding again only the pairs of the triangles that left
  /// their grown boxes, or whose patch turned flat or stopped being flat, alone or with a
  /// neighbour (pairEligible changed for the pairs within it or across to it), as filterIfStill()
  /// found them; false where it must be rebuilt whole.
  bool update(BroadPhase& broadPhase, const BroadPhaseInput& input);
  enum class Still {
    Filtered,  ///< no box left its grown box: `pairs` is filter()'s
    Left,      ///< some did: leftChunks_ holds them for update()
    NotMade,   ///< the cache was not made for these triangles: rebuild()
  };
  /// The scan for triangles that left their grown boxes and filter() in one parallel loop.
  Still filterIfStill(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs,
                      std::span<const std::uint8_t> involving);
  /// Whether the cache was made for `input`'s triangles and surfaces; sets turned_ if so.
  bool markTurned(const BroadPhaseInput& input);
  static std::size_t scanChunks(std::size_t triangles);
  /// Chunk `chunk` of `chunks` of the scan for triangles that left, into leftChunks_.
  void scanChunk(const BroadPhaseInput& input, std::size_t chunk, std::size_t chunks);
  std::size_t filterChunks() const;
  /// Chunk `chunk` of `chunks` of filter(), into buffers_.
  void filterChunk(const BroadPhaseInput& input, std::span<const std::uint8_t> involving,
                   std::size_t chunk, std::size_t chunks);
  /// `box` grown by the margin on every side.
  Box3 grow(const Box3& box) const;
  BroadPhaseInput grownInput(const BroadPhaseInput& input) const;

  double marginFraction_;
  Scalar margin_ = -1;  ///< scene units; negative until the first rebuild
  std::vector<Box3> grown_;
  std::vector<TrianglePair> cached_;
  ChunkBuffers<TrianglePair> buffers_;  ///< per filter chunk
  ChunkBuffers<Index> leftChunks_;      ///< per chunk: the triangles that left
  std::vector<Index> left_;             ///< all of them, ascending
  std::vector<char> hasLeft_;           ///< per triangle
  std::vector<std::uint8_t> flatSeen_;  ///< the patches' flatness the cached pairs were found with
  /// The same of each pair of neighbouring patches taken as one.
  std::vector<std::uint8_t> flatWithSeen_;
  /// Per patch: flat then and not now, or the other way, alone or with a neighbour.
  std::vector<std::uint8_t> turned_;
  bool anyTurned_ = false;
  std::vector<TrianglePair> fresh_, merged_;
  std::size_t surfaceCount_ = 0;
  std::size_t rebuilds_ = 0, updates_ = 0;
  std::size_t updatedSinceRebuild_ = 0;
};

}  // namespace softbake
