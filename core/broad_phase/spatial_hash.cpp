// Teschner et al. 2003, adapted to triangle pairs and made exact.
//
// Teschner hashes the vertices and lets each tetrahedron look up the cells its box covers. Here
// both sides are triangles: every triangle is entered under each cell its box covers, and every
// triangle looks up the cells of its box. Two boxes that overlap at a point p both cover the cell
// holding p (cell coordinates are monotone), so the pair meets in that cell's bucket; it is taken
// only there (the "owner" cell, that of p = the larger of the two lower corners), so a pair is
// listed once however many cells the two boxes share. Hash collisions only cost a box test.
//
// Cell size: the mean, over the moving surfaces' triangles, of the longest side of the triangle
// box, recomputed each step. The boxes are swept and inflated, so this tracks Teschner's "average
// edge length" of what actually moves, and static geometry (often a few huge ground triangles)
// does not set it.
//
// Bounded memory: one grid would enter a huge static triangle under millions of cells. So the
// grid has levels, level k with cells 2^k times larger, and a triangle lives on the finest level
// where its box covers at most kMaxCellsPerAxis cells per axis (a hierarchical hash grid). Each
// triangle then makes at most 64 entries. A pair whose triangles live on levels a ≤ b is looked up
// by the triangle on level a, in level b's cells (at most 3 per axis, as they are coarser): so
// every triangle queries its own level and each coarser level in use.

#include "core/broad_phase/spatial_hash.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace softbake {

namespace {

/// Keeps cell coordinates below 2^32 across the scene (as BoxHashGrid assumes).
constexpr double kMaxCellsAcross = 4294967296.0;
/// Triangles per query task: a few microseconds of lookups.
constexpr std::size_t kQueryGrain = 256;
constexpr std::size_t kBoxGrain = 4096;
/// Mixed into the hash so the levels' cells do not pile onto the same buckets.
constexpr std::uint64_t kLevelPrime = 2654435761u;

struct SideSum {
  double sum = 0;
  std::size_t count = 0;
};

}  // namespace

void SpatialHashBroadPhase::findPairs(const BroadPhaseInput& input,
                                      std::vector<TrianglePair>& pairs) {
  chooseGrid(input);
  fillTable(input);
  query(input, pairs);
}

void SpatialHashBroadPhase::chooseGrid(const BroadPhaseInput& input) {
  const std::size_t n = input.triangleBox.size();
  const Box3 bounds = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, kBoxGrain), Box3(),
      [&](const tbb::blocked_range<std::size_t>& range, Box3 box) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) box.extend(input.triangleBox[t]);
        return box;
      },
      [](Box3 a, const Box3& b) { return a.extend(b); });

  // Deterministic reduction: the same sum, to the last bit, on any thread count.
  auto sides = [&](bool movingOnly) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, n, kBoxGrain), SideSum(),
        [&](const tbb::blocked_range<std::size_t>& range, SideSum sum) {
          for (std::size_t t = range.begin(); t != range.end(); ++t) {
            if (movingOnly && !input.surfaces[input.triangleSurface[t]].moving) continue;
            const Box3& box = input.triangleBox[t];
            sum.sum += (box.max().cast<double>() - box.min().cast<double>()).maxCoeff();
            ++sum.count;
          }
          return sum;
        },
        [](SideSum a, const SideSum& b) {
          return SideSum{a.sum + b.sum, a.count + b.count};
        });
  };
  SideSum sum = sides(true);
  if (sum.count == 0) sum = sides(false);  // nothing moves: the pairs are self-collisions only
  const double span = bounds.isEmpty()
                          ? 0.0
                          : (bounds.max().cast<double>() - bounds.min().cast<double>()).maxCoeff();
  double cellSize = std::max(sum.count ? sum.sum / double(sum.count) : 0.0, span / kMaxCellsAcross);
  if (!(cellSize > 0) || !std::isfinite(cellSize)) cellSize = 1;

  for (int level = 0; level <= kMaxLevels; ++level) {
    BoxHashGrid& grid = grids_[level];
    grid.origin = bounds.isEmpty() ? Vec3d::Zero() : Vec3d(bounds.min().cast<double>());
    grid.cellSize.setConstant(std::ldexp(cellSize, level));
    grid.inverseCellSize = grid.cellSize.cwiseInverse();
  }
  stats_.cellSize = cellSize;
}

std::uint32_t SpatialHashBroadPhase::bucketOf(const Cell& cell, int level) const {
  return std::uint32_t((BoxHashGrid::hash(cell) + std::uint64_t(level) * kLevelPrime) &
                       bucketMask_);
}

void SpatialHashBroadPhase::fillTable(const BroadPhaseInput& input) {
  const std::size_t n = input.triangleBox.size();
  cells_.resize(n);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, kBoxGrain),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          const Box3& box = input.triangleBox[t];
          const double side = (box.max().cast<double>() - box.min().cast<double>()).maxCoeff();
          // First guess: boxes up to (kMaxCellsPerAxis − 1) cells long always fit.
          const double ratio = side / ((kMaxCellsPerAxis - 1) * grids_[0].cellSize.x());
          int level = ratio > 1 ? int(std::ceil(std::log2(std::min(ratio, 1e300)))) : 0;
          level = std::min(level, kMaxLevels);
          Cell lo, hi;
          for (;; ++level) {
            lo = grids_[level].cell(box.min());
            hi = grids_[level].cell(box.max());
            if ((hi - lo).maxCoeff() < kMaxCellsPerAxis || level == kMaxLevels) break;
          }
          TriangleCells& mine = cells_[t];
          mine.lo = lo;
          mine.level = std::uint8_t(level);
          // Only a non-finite box can still be too long here; such boxes are outside
          // the contract, and clamping keeps the table bounded.
          for (int axis = 0; axis < 3; ++axis)
            mine.span[axis] = std::uint8_t(
                std::clamp<std::int64_t>(hi[axis] - lo[axis] + 1, 1, kMaxCellsPerAxis));
        }
      });

  entryStart_.resize(n + 1);
  entryStart_[0] = 0;
  std::uint64_t usedLevelMask = 0;
  for (std::size_t t = 0; t < n; ++t) {
    const TriangleCells& mine = cells_[t];
    entryStart_[t + 1] = entryStart_[t] + mine.span[0] * mine.span[1] * mine.span[2];
    usedLevelMask |= std::uint64_t(1) << mine.level;
  }
  usedLevels_.clear();
  for (int level = 0; level <= kMaxLevels; ++level)
    if (usedLevelMask >> level & 1) usedLevels_.push_back(level);

  // Load factor ≤ 1/2; a power of two makes "mod buckets" a mask (the primes are odd, so every
  // axis term still reaches every bucket).
  const std::size_t entries = entryStart_[n];
  const std::size_t bucketCount = std::bit_ceil(std::max<std::size_t>(2 * entries, 1));
  bucketMask_ = bucketCount - 1;
  entryBucket_.resize(entries);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kBoxGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const TriangleCells& mine = cells_[t];
                        std::uint32_t e = entryStart_[t];
                        for (int z = 0; z < mine.span[2]; ++z)
                          for (int y = 0; y < mine.span[1]; ++y)
                            for (int x = 0; x < mine.span[0]; ++x)
                              entryBucket_[e++] = bucketOf(mine.lo + Cell(x, y, z), mine.level);
                      }
                    });

  // Counting sort of the entries by bucket.
  bucketStart_.assign(bucketCount + 1, 0);
  for (std::uint32_t bucket : entryBucket_) ++bucketStart_[bucket + 1];
  for (std::size_t b = 0; b < bucketCount; ++b) bucketStart_[b + 1] += bucketStart_[b];
  bucketFill_.assign(bucketStart_.begin(), bucketStart_.end() - 1);
  bucketEntries_.resize(entries);
  for (std::size_t t = 0; t < n; ++t) {
    const Entry entry{Index(t), input.triangleSurface[t], cells_[t].level};
    for (std::uint32_t e = entryStart_[t]; e < entryStart_[t + 1]; ++e)
      bucketEntries_[bucketFill_[entryBucket_[e]]++] = entry;
  }

  stats_.levels = usedLevels_.empty() ? 0 : usedLevels_.back() + 1;
  stats_.entries = entries;
  stats_.buckets = bucketCount;
}

void SpatialHashBroadPhase::query(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) {
  const std::size_t n = input.triangleBox.size();
  const std::size_t chunks = (n + kQueryGrain - 1) / kQueryGrain;
  buffers_.reset(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<TrianglePair>& out = buffers_[chunk];
    const Index stop = Index(std::min(n, (chunk + 1) * kQueryGrain));
    for (Index i = Index(chunk * kQueryGrain); i < stop; ++i) {
      const Box3& box = input.triangleBox[i];
      const int own = cells_[i].level;
      const Index surface = input.triangleSurface[i];
      const bool moving = input.surfaces[surface].moving;
      const bool self = input.surfaces[surface].selfCollision;
      for (int level : usedLevels_) {
        if (level < own) continue;  // finer triangles look this one up themselves
        const BoxHashGrid& grid = grids_[level];
        const Cell lo = grid.cell(box.min());
        // Finite boxes cover at most kMaxCellsPerAxis cells here; the cap bounds the others.
        const Cell hi =
            grid.cell(box.max()).cwiseMin((lo.array() + (kMaxCellsPerAxis - 1)).matrix());
        for (std::int64_t z = lo.z(); z <= hi.z(); ++z)
          for (std::int64_t y = lo.y(); y <= hi.y(); ++y)
            for (std::int64_t x = lo.x(); x <= hi.x(); ++x) {
              const Cell cell(x, y, z);
              const std::uint32_t bucket = bucketOf(cell, level);
              for (std::uint32_t e = bucketStart_[bucket]; e < bucketStart_[bucket + 1]; ++e) {
                const Entry entry = bucketEntries_[e];
                const Index j = entry.triangle;
                if (int(entry.level) != level) continue;
                if (level == own && j <= i) continue;  // same level: the lower index asks
                // The surface half of pairEligible, before any box is read.
                if (entry.surface == surface ? !self
                                             : !moving && !input.surfaces[entry.surface].moving)
                  continue;
                const Box3& other = input.triangleBox[j];
                if (!box.intersects(other)) continue;
                if (grid.cell(box.min().cwiseMax(other.min())) != cell) continue;  // not owner
                if (!pairEligible(input, i, j)) continue;
                out.push_back(i < j ? TrianglePair{i, j} : TrianglePair{j, i});
              }
            }
      }
    }
  });
  buffers_.mergeInto(pairs);
}

}  // namespace softbake
