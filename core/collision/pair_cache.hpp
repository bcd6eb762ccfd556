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

#include <vector>

#include "core/collision/broad_phase.hpp"

namespace softbake {

class PairCache {
 public:
  /// `margin`: how far, as a fraction of the mean triangle box size at the first step, each box
  /// is grown. Larger: fewer rebuilds, more cached pairs to filter.
  explicit PairCache(double margin = 0.25) : marginFraction_(margin) {}

  /// The exact overlapping eligible pairs of `input`, sorted, using `broadPhase` only when some
  /// box has left its grown box (or on the first call, or when the surfaces changed).
  void findPairs(BroadPhase& broadPhase, const BroadPhaseInput& input,
                 std::vector<TrianglePair>& pairs);

  /// The same pairs from the cache alone, for other boxes of the same triangles (those of a later
  /// stage of the substep), when every box lies inside its grown box; otherwise false. Uses
  /// scratch buffers: not at the same time as findPairs().
  bool findCachedPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs);

  std::size_t rebuilds() const { return rebuilds_; }

 private:
  void filter(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs);
  bool stillValid(const BroadPhaseInput& input) const;
  void rebuild(BroadPhase& broadPhase, const BroadPhaseInput& input);

  double marginFraction_;
  Scalar margin_ = -1;  ///< scene units; negative until the first rebuild
  std::vector<Box3> grown_;
  std::vector<TrianglePair> cached_;
  broad_phase_detail::PairBuffers buffers_;  ///< per filter chunk
  std::size_t surfaceCount_ = 0;
  std::size_t rebuilds_ = 0;
};

}  // namespace softbake
