#pragma once
/// Spatial hashing after Teschner et al. 2003, "Optimized Spatial Hashing for Collision Detection
/// of Deformable Objects" ("spatialhash"): triangles are entered in a hash table under every grid
/// cell their box covers, and each triangle then looks up the cells of its own box.
/// Output: see core/broad_phase/broad_phase.hpp.

#include <array>
#include <cstdint>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/broad_phase/sbhash.hpp"  // BoxHashGrid: the same cell hash, one grid per level

namespace softbake {

/// What the latest findPairs saw, for tests and tuning.
struct SpatialHashStats {
  double cellSize = 0;      ///< level-0 cell side (see the .cpp for the rule)
  int levels = 0;           ///< grid levels in use: level k has cells of side cellSize·2^k
  std::size_t entries = 0;  ///< (cell, triangle) entries in the table
  std::size_t buckets = 0;  ///< size of the table
};

class SpatialHashBroadPhase final : public BroadPhase {
 public:
  /// A triangle covering more cells than this along an axis moves to a coarser level, so no
  /// triangle enters more than 4³ = 64 cells, however large it is.
  static constexpr int kMaxCellsPerAxis = 4;
  /// Levels double the cell size; 40 doublings pass any scene, since cells start at ≥ 2^-32 of it.
  static constexpr int kMaxLevels = 40;

  void findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) override;
  BroadPhaseKind kind() const override { return BroadPhaseKind::SpatialHash; }

  const SpatialHashStats& lastStats() const { return stats_; }

 private:
  using Cell = BoxHashGrid::Cell;

  /// A triangle's place in the grid: the cells lo + [0, span) on its level.
  struct TriangleCells {
    Cell lo;
    std::array<std::uint8_t, 3> span;
    std::uint8_t level;
  };

  void chooseGrid(const BroadPhaseInput& input);
  std::uint32_t bucketOf(const Cell& cell, int level) const;
  void fillTable(const BroadPhaseInput& input);
  void query(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs);

  std::array<BoxHashGrid, kMaxLevels + 1> grids_;  ///< level k: cells of side cellSize·2^k
  std::uint64_t bucketMask_ = 0;
  std::vector<int> usedLevels_;  ///< ascending levels holding at least one triangle

  std::vector<TriangleCells> cells_;        ///< per triangle
  std::vector<std::uint32_t> entryStart_;   ///< per triangle: first entry (prefix sum)
  std::vector<std::uint32_t> entryBucket_;  ///< per entry
  std::vector<std::uint32_t> bucketStart_;  ///< hash table (CSR): entries of each bucket
  std::vector<std::uint32_t> bucketFill_;   ///< scratch for the counting sort
  /// What a lookup needs of a triangle without touching its other data.
  struct Entry {
    Index triangle;
    std::uint32_t surface : 26;  ///< a scene has far fewer than 2^26 surfaces
    std::uint32_t level : 6;     ///< ≤ kMaxLevels
  };
  std::vector<Entry> bucketEntries_;  ///< grouped by bucket

  broad_phase_detail::PairBuffers buffers_;
  SpatialHashStats stats_;
};

}  // namespace softbake
