#pragma once
/// Broad phase: which collision triangles may touch this step.
///
/// Every broad phase returns exactly the same thing — the eligible triangle pairs whose boxes
/// overlap (closed boxes: touching counts), each pair once as (lower index, higher index), sorted —
/// so the narrow phase, the response and the output are identical whichever one runs, and
/// `BroadPhaseKind::BruteForce` is the reference the others are tested against.
///
/// Eligibility (pairEligible): triangles of two different surfaces, unless both are static; two
/// triangles of one surface only when that surface self-collides, they share no vertex and they
/// do not lie in one patch, or two neighbouring ones, flat this step (normal cones:
/// core/collision/self_patches.hpp).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/parallel.hpp"
#include "core/scene/settings.hpp"
#include "core/types.hpp"

namespace softbake {

using Box3 = Eigen::AlignedBox<Scalar, 3>;

/// AlignedBox::intersects() with & instead of &&: one branch for the caller instead of up to six.
/// The broad and narrow phases test boxes by the thousand a step, with outcomes in no pattern a
/// branch predictor learns. The same answer, NaN included.
inline bool overlaps(const Box3& a, const Box3& b) {
  return bool(unsigned(a.min().x() <= b.max().x()) & unsigned(a.min().y() <= b.max().y()) &
              unsigned(a.min().z() <= b.max().z()) & unsigned(b.min().x() <= a.max().x()) &
              unsigned(b.min().y() <= a.max().y()) & unsigned(b.min().z() <= a.max().z()));
}

/// A soft body or a static mesh: a contiguous range of collision triangles.
struct CollisionSurface {
  Index firstTriangle = 0, triangleCount = 0;
  bool moving = true;          ///< false for static colliders: their boxes never change
  bool selfCollision = false;  ///< test the surface's own non-adjacent triangles against each other
};

/// What a broad phase reads. Surfaces are in order and their triangle ranges tile [0, boxes).
struct BroadPhaseInput {
  std::span<const Box3> triangleBox;  ///< per triangle: swept over the step, inflated
  std::span<const Triangle>
      triangleVertices;                    ///< per triangle, in one vertex space for all surfaces
  std::span<const Index> triangleSurface;  ///< per triangle: its surface
  std::span<const CollisionSurface> surfaces;
  /// Normal-cone culling (core/collision/self_patches.hpp): per triangle its patch or kNoPatch,
  /// per patch whether it is flat this step, and per patch its neighbouring patches (from
  /// patchNeighbourStart[p], ascending), each with whether the two are flat as one this step.
  /// Empty: no pair is culled.
  std::span<const Index> trianglePatch = {};
  std::span<const std::uint8_t> patchFlat = {};
  std::span<const Index> patchNeighbourStart = {}, patchNeighbour = {};
  std::span<const std::uint8_t> patchFlatWith = {};
  /// Whether patches p and q (the same, or neighbours) are flat as one this step; false where
  /// either is no patch (~0).
  bool flatTogether(Index p, Index q) const {
    if (p >= patchFlat.size() || q >= patchFlat.size()) return false;
    if (p == q) return patchFlat[p];
    if (patchFlatWith.empty() || !patchFlat[p] || !patchFlat[q]) return false;
    for (Index k = patchNeighbourStart[p]; k < patchNeighbourStart[p + 1]; ++k)
      if (patchNeighbour[k] >= q) return patchNeighbour[k] == q && patchFlatWith[k];
    return false;
  }
  /// Whether triangles i and j lie in one patch, or two neighbouring ones, flat this step.
  bool inFlatPatches(Index i, Index j) const {
    return !patchFlat.empty() && flatTogether(trianglePatch[i], trianglePatch[j]);
  }
};

struct TrianglePair {
  Index first, second;  ///< first < second
  friend bool operator==(const TrianglePair&, const TrianglePair&) = default;
  friend auto operator<=>(const TrianglePair&, const TrianglePair&) = default;
};

/// The eligibility rule above, for triangles i ≠ j.
bool pairEligible(const BroadPhaseInput& input, Index i, Index j);

struct BroadPhaseOptions {
  int subdivisionLevels = 3;  ///< sbhash: level L splits each surface box into 2^L per axis
};

class BroadPhase {
 public:
  virtual ~BroadPhase() = default;
  /// Replaces `pairs` with this step's candidate pairs (see the file comment). Buffers inside the
  /// broad phase and `pairs` keep their capacity, so a warmed-up step allocates nothing.
  virtual void findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) = 0;
  /// Replaces `pairs` with the pairs findPairs would list that have at least one triangle in
  /// `triangles` (ascending), sorted and unique, for a caller that knows the other pairs already
  /// (the pair cache, when a few triangles left their grown boxes). Of everything the latest call
  /// (this or findPairs) saw, only the boxes of `triangles` may differ. False where this broad
  /// phase cannot answer for a few triangles alone, or saw no findPairs call on these surfaces;
  /// the caller then runs findPairs.
  virtual bool findPairsInvolving(const BroadPhaseInput& input, std::span<const Index> triangles,
                                  std::vector<TrianglePair>& pairs) {
    (void)input, (void)triangles, (void)pairs;
    return false;
  }
  virtual BroadPhaseKind kind() const = 0;
};

std::unique_ptr<BroadPhase> makeBroadPhase(BroadPhaseKind kind,
                                           const BroadPhaseOptions& options = {});

/// What the broad phases share (core/broad_phase/broad_phase.cpp), so each states the output
/// contract once. For implementers of BroadPhase, not for callers.
namespace broad_phase_detail {

/// Appends (min, max) of i ≠ j when their boxes overlap and pairEligible allows them. The box
/// test comes first: it is inline and rejects most pairs before the out-of-line rule runs.
inline void addIfCandidate(const BroadPhaseInput& input, Index i, Index j,
                           std::vector<TrianglePair>& out) {
  if (!input.triangleBox[i].intersects(input.triangleBox[j]) || !pairEligible(input, i, j)) return;
  out.push_back(i < j ? TrianglePair{i, j} : TrianglePair{j, i});
}

/// The surface a broad phase built its per-surface cache (leaves, a tree) for. A static surface's
/// cache is kept across steps as long as the surface covers the same triangles and stays static.
struct CachedSurface {
  Index firstTriangle = 0, triangleCount = 0;
  bool moving = true;
  bool covers(const CollisionSurface& given) const {
    return firstTriangle == given.firstTriangle && triangleCount == given.triangleCount &&
           moving == given.moving;
  }
  /// Takes over `given`; true when it differs from the surface cached so far.
  bool adopt(const CollisionSurface& given) {
    const bool changed = !covers(given);
    firstTriangle = given.firstTriangle;
    triangleCount = given.triangleCount;
    moving = given.moving;
    return changed;
  }
};

/// Sorts and drops repeats: the one output order every broad phase promises. A least-significant-
/// digit radix sort over the bytes the indices use (four passes at 10 000 triangles), in `scratch`
/// of the same size: a broad phase's pairs are tens of thousands, where it is several times
/// faster than a comparison sort. PairBuffers::mergeInto() sorts millions in parallel buckets.
void sortUnique(std::vector<TrianglePair>& pairs, std::vector<TrianglePair>& scratch);

/// Pairs found in parallel, one buffer per chunk of work (ChunkBuffers), merged sorted.
class PairBuffers {
 public:
  /// `chunks` empty buffers.
  void reset(std::size_t chunks) { buffers_.reset(chunks); }
  std::vector<TrianglePair>& operator[](std::size_t chunk) { return buffers_[chunk]; }
  /// Replaces `pairs` with every buffer's pairs, sorted and unique. Many pairs (a rebuild at a
  /// million faces) are sorted in parallel, in buckets by the high bits of `first`.
  void mergeInto(std::vector<TrianglePair>& pairs);

 private:
  ChunkBuffers<TrianglePair> buffers_;
  std::vector<TrianglePair> scratch_;  ///< the radix sort's other half
  /// The bucketed sort of many pairs: where each buffer's part of each bucket goes, where each
  /// bucket ends, how many of its pairs are unique, and where those go.
  std::vector<std::size_t> bucketStart_, bucketEnd_, bucketKept_, bucketPacked_;
};

}  // namespace broad_phase_detail

}  // namespace softbake
