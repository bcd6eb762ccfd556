#pragma once
/// The paper's broad phase ("sbhash"): multi-level subdivided bounding boxes and the box hash
/// function (Mesit & Guha, §2.1–2.2).
///
/// Each step, every moving surface's box (the union of its triangle boxes) is cut into 2^L cells
/// per axis; each non-empty cell is a leaf holding the triangles whose boxes reach into it (static
/// surfaces are cut once). The 8 corners of every leaf box are hashed into a bucket table; leaves
/// sharing a bucket are candidate leaf pairs, and the triangles of overlapping candidate leaves
/// give the triangle pairs. Surfaces whose box meets no other are skipped. Output: see
/// core/broad_phase/broad_phase.hpp; the argument that nothing is missed: the .cpp.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"

namespace softbake {

/// The grid whose cells the box hash function hashes: `h = (⌊x/cx⌋·p1 + ⌊y/cy⌋·p2 + ⌊z/cz⌋·p3)
/// mod buckets`, with the primes of Teschner et al. 2003. Cell coordinates are counted from
/// `origin` (the scene's lower corner) rather than from the world origin: a translated grid hashes
/// as well, and small coordinates keep the rounding argument of fit() valid anywhere in the world.
struct BoxHashGrid {
  using Cell = Eigen::Matrix<std::int64_t, 3, 1>;

  Vec3d origin = Vec3d::Zero();
  Vec3d cellSize = Vec3d::Ones();
  Vec3d inverseCellSize = Vec3d::Ones();

  /// The grid for leaf boxes inside `bounds` whose largest extents are `maxExtent` per axis: cells
  /// at least that large (see the .cpp for why), anchored at bounds.min().
  static BoxHashGrid fit(const Box3& bounds, const Vec3d& maxExtent);

  /// The cell holding `point`. Monotone along each axis, which the completeness argument needs.
  Cell cell(const Vec3& point) const;

  /// The paper's hash of a cell; reduce it with `& (buckets − 1)` for a power-of-two table.
  static std::uint64_t hash(const Cell& cell) {
    // Unsigned arithmetic wraps instead of overflowing, so any cell coordinate is fine.
    return std::uint64_t(cell.x()) * 73856093u + std::uint64_t(cell.y()) * 19349663u +
           std::uint64_t(cell.z()) * 83492791u;
  }
};

/// What the latest findPairs saw, for tests and tuning.
struct SbhashStats {
  std::size_t rebuiltSurfaces = 0;      ///< surfaces whose leaves were built (static ones: once)
  std::size_t activeSurfaces = 0;       ///< surfaces past the surface-box test (see the .cpp)
  std::size_t leaves = 0;               ///< non-empty leaves of the active surfaces, all hashed
  std::size_t buckets = 0;              ///< size of the bucket table
  std::size_t candidateLeafPairs = 0;   ///< overlapping, eligible leaf pairs, each once
  Vec3d cellSize = Vec3d::Zero();       ///< the hash grid's cell size
  Vec3d maxLeafExtent = Vec3d::Zero();  ///< largest leaf box side along each axis
};

class SbhashBroadPhase final : public BroadPhase {
 public:
  /// `subdivisionLevels` L gives 2^L cells per axis per surface; clamped to [0, kMaxLevels].
  explicit SbhashBroadPhase(int subdivisionLevels = 3);

  /// 8^6 = 262144 cells per surface: a per-surface count table of 1 MiB. Beyond that the table
  /// costs more than the leaves save.
  static constexpr int kMaxLevels = 6;

  void findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) override;
  BroadPhaseKind kind() const override { return BroadPhaseKind::Sbhash; }

  int subdivisionLevels() const { return levels_; }
  const SbhashStats& lastStats() const { return stats_; }
  /// The leaf boxes hashed by the latest findPairs.
  std::span<const Box3> lastLeafBoxes() const { return leafBox_; }

 private:
  /// One axis of a surface's subdivision: cell k is the closed interval [cut[k], cut[k+1]].
  struct AxisCuts {
    std::array<Scalar, (1 << kMaxLevels) + 1> cut;
    Scalar lo = 0;
    double scale = 0;  ///< cells per unit length, for the first guess
    int n = 1;
    void set(Scalar low, Scalar high, int cells);

    /// The largest k < n with cut[k] ≤ x (0 below lo): monotone in x, and x ∈ [cut[k], cut[k+1]]
    /// for every x in [lo, hi].
    int cell(Scalar x) const {
      const double guess = (double(x) - double(lo)) * scale;
      int k = guess >= 0 ? (guess < n ? int(guess) : n - 1) : 0;  // NaN → 0
      while (k > 0 && x < cut[k]) --k;
      while (k < n - 1 && x >= cut[k + 1]) ++k;
      return k;
    }
  };

  struct Leaf {
    Box3 box;                          ///< union of its triangles' boxes, clipped to its cell
    Index begin, end;                  ///< its triangles: SurfaceLeaves::triangles[begin, end)
    std::array<std::uint8_t, 3> cell;  ///< its cell in the subdivision
  };

  /// One surface's subdivision. Kept across steps: a static surface's is built once, a moving
  /// surface's buffers keep their capacity.
  struct SurfaceLeaves : broad_phase_detail::CachedSurface {
    bool boxKnown = false;  ///< `box` is current (a static surface's stays current)
    bool built = false;     ///< `leaves` are current (a static surface's stay current)
    Box3 box;               ///< union of the triangle boxes
    std::array<AxisCuts, 3> cuts;
    std::vector<Leaf> leaves;
    std::vector<Index> triangles;  ///< triangle ids grouped by cell (counting sort)
    std::vector<Index> cellStart;  ///< scratch: per cell, its first entry in `triangles`
    std::vector<Index> cellFill;   ///< scratch: per cell, the next entry to write
    /// scratch: per triangle, its first and last cell along x, y and z
    std::vector<std::array<std::uint8_t, 6>> triangleCells;

    /// Whether the point lies in `leaf`'s cell, by the same rule that assigned the triangles.
    bool owns(const Leaf& leaf, const Vec3& point) const {
      return cuts[0].cell(point.x()) == leaf.cell[0] && cuts[1].cell(point.y()) == leaf.cell[1] &&
             cuts[2].cell(point.z()) == leaf.cell[2];
    }
  };

  /// Where each leaf's corners landed: its distinct buckets, ascending.
  struct LeafBuckets {
    std::array<std::uint64_t, 8> bucket;  ///< hashes, then reduced to bucket ids
    std::uint32_t count;
  };

  void syncSurfaces(const BroadPhaseInput& input);
  void buildLeaves(const BroadPhaseInput& input, SurfaceLeaves& surface) const;
  void markActiveSurfaces(const BroadPhaseInput& input);
  void gatherLeaves();
  void hashLeaves();
  void findLeafPairs(const BroadPhaseInput& input);
  void trianglePairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs);

  int levels_;
  std::vector<SurfaceLeaves> surfaces_;
  std::vector<Index> activeSurfaces_;  ///< this step's surfaces worth subdividing
  std::vector<Index> toBuild_;         ///< scratch: surfaces whose leaves this step rebuilds

  // This step's leaves of the active surfaces, flattened.
  std::vector<Box3> leafBox_;
  std::vector<Index> leafSurface_;
  std::vector<Index> leafIndex_;  ///< in its surface's `leaves`
  std::vector<LeafBuckets> leafBuckets_;

  std::vector<std::uint32_t> bucketStart_;  ///< bucket table (CSR): entries of bucket b
  std::vector<std::uint32_t> bucketFill_;   ///< scratch for the counting sort
  std::vector<Index> bucketLeaves_;         ///< leaf ids, grouped by bucket

  std::vector<std::array<Index, 2>> leafPairs_;
  /// A triangle's box on the sweep axis (x), for the sort-and-sweep inside a leaf pair.
  struct SweepEntry {
    Scalar lo, hi;
    Index triangle;
  };
  /// Per chunk: the triangles of each leaf near the other leaf, sorted by `lo`.
  std::vector<std::vector<SweepEntry>> nearA_, nearB_;
  broad_phase_detail::PairBuffers buffers_;
  BoxHashGrid grid_;
  SbhashStats stats_;
};

}  // namespace softbake
