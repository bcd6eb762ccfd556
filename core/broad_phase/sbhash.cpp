// Mesit & Guha §2.1–2.2: multi-level subdivided bounding boxes and the box hash function, made
// exact: every pair of overlapping triangle boxes is found, so this broad phase returns what
// brute force returns. Why nothing is missed is argued where each step could lose a pair:
//
//  1. Surfaces. A surface whose box meets no other surface's box (that could pair with it) and
//     that does not self-collide has no pairs: it is not subdivided or hashed this step. This is
//     the hierarchy used: surface box → leaf boxes → triangle boxes, each level culling the next.
//  2. Leaves (buildLeaves). Take triangles t of surface S and u of surface T whose boxes overlap,
//     and p a point of both boxes. p lies in one cell of S's subdivision, t reaches into that cell,
//     and the leaf box (t's box ∪ … clipped to the cell) still contains p: clipping only removes
//     what lies outside the cell, and p is inside it. The same holds for u in T. So the leaf boxes
//     holding t and u overlap, at p.
//  3. Hash (BoxHashGrid). Two overlapping leaf boxes always put a corner each into one grid cell,
//     so they share a bucket (see BoxHashGrid::fit).
//  4. Self-collision: if S = T, step 2 puts t and u in the same leaf, the one holding p. So a
//     self-colliding surface pairs each leaf with itself, and needs no pairs of its own different
//     leaves. ("Non-adjacent leaves only" would miss every fold that fits inside one leaf.)
//  5. Triangles of a leaf pair (a, b). Let p be the lower corner of box(t) ∩ box(u) (the larger
//     of their lower corners). The leaf pair whose cells hold p is a candidate (steps 2–3), and it
//     is the only one that reports (t, u): a pair is listed once however many leaves its
//     triangles span, and no sort is needed to remove repeats. In that leaf pair p lies in both
//     leaf boxes, so only the triangles of a whose boxes meet b's box (and those of b meeting a's
//     box) need to be tried against each other.

#include "core/broad_phase/sbhash.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace softbake {

namespace {

/// Cells are this much larger than the largest leaf box: room for the rounding of the cell
/// coordinates (see BoxHashGrid::fit).
constexpr double kCellMargin = 1.0 / 1024;
/// At most this many cells across the scene per axis, so that cell coordinates stay below 2^32
/// and their rounding error below 2^-19 of a cell.
constexpr double kMaxCellsAcross = 4294967296.0;
/// Cell coordinates are clamped to ±2^62: clamping is monotone, so the argument survives, and the
/// conversion from double stays defined for any input, NaN included.
constexpr double kCellLimit = 4611686018427387904.0;
/// Leaf pairs vary a lot in cost; this many chunks lets TBB balance them on any thread count.
constexpr std::size_t kMaxChunks = 256;

std::int64_t cellCoordinate(double offset, double inverseCellSize) {
  const double q = offset * inverseCellSize;
  if (!(q > -kCellLimit)) return -std::int64_t(kCellLimit);  // NaN too
  if (!(q < kCellLimit)) return std::int64_t(kCellLimit);
  // floor without the libm call: truncate, then step down for negative fractions
  const std::int64_t truncated = std::int64_t(q);
  return double(truncated) > q ? truncated - 1 : truncated;
}

Box3 unionOfBoxes(std::span<const Box3> boxes, Index begin, Index end) {
  Box3 box;  // empty
  for (Index t = begin; t < end; ++t) box.extend(boxes[t]);
  return box;
}

}  // namespace

// Two leaf boxes that overlap always have a corner each in one common cell, when each cell side is
// at least the largest leaf box side along that axis. Per axis: take intervals [a0, a1], [b0, b1]
// of length ≤ c that overlap, with a0 ≤ b0 (else swap names); then a0 ≤ b0 ≤ a1. Cell coordinates
// q(x) = ⌊(x − origin)/c⌋ are monotone, and q(a1) − q(a0) ≤ 1 because a1 − a0 ≤ c; so q(b0) is
// q(a0) or q(a1): an endpoint of one interval shares a cell with an endpoint of the other.
// Taking those endpoints on all three axes names one corner of each box, and the two corners have
// the same cell on every axis, hence the same hash and bucket.
//
// In floating point, "q(a1) − q(a0) ≤ 1" needs the computed (a1 − a0)/c below 1: c is made
// (1 + 2^-10) times the largest extent (extents measured in double), and offsets from the origin
// stay below 2^32 cells, so the rounding of offset·(1/c) (< 2^-19) cannot reach the margin.
BoxHashGrid BoxHashGrid::fit(const Box3& bounds, const Vec3d& maxExtent) {
  BoxHashGrid grid;
  for (int axis = 0; axis < 3; ++axis) {
    const bool empty = bounds.isEmpty();
    grid.origin[axis] = empty ? 0.0 : double(bounds.min()[axis]);
    const double span = empty ? 0.0 : double(bounds.max()[axis]) - grid.origin[axis];
    double size = std::max(maxExtent[axis] * (1 + kCellMargin), span / kMaxCellsAcross);
    if (!(size > 0) || !std::isfinite(size)) size = 1;  // flat or empty: any cell size works
    grid.cellSize[axis] = size;
    grid.inverseCellSize[axis] = 1 / size;
  }
  return grid;
}

BoxHashGrid::Cell BoxHashGrid::cell(const Vec3& point) const {
  Cell result;
  for (int axis = 0; axis < 3; ++axis)
    result[axis] = cellCoordinate(double(point[axis]) - origin[axis], inverseCellSize[axis]);
  return result;
}

// The boundaries are rounded once, to Scalar, and then the triangle assignment, the leaf clipping
// and the owner test all use the same numbers, so a point always lies inside the closed interval
// of the cell it is assigned to.
void SbhashBroadPhase::AxisCuts::set(Scalar low, Scalar high, int cells) {
  lo = low;
  n = cells;
  const double span = double(high) - double(low);
  scale = span > 0 ? n / span : 0.0;
  for (int k = 0; k < n; ++k)
    cut[k] = std::clamp(Scalar(double(low) + span * k / n), low, high);  // monotone in k
  cut[n] = high;
}

SbhashBroadPhase::SbhashBroadPhase(int subdivisionLevels)
    : levels_(std::clamp(subdivisionLevels, 0, kMaxLevels)) {}

void SbhashBroadPhase::findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) {
  syncSurfaces(input);
  markActiveSurfaces(input);

  toBuild_.clear();
  for (Index s : activeSurfaces_)
    if (surfaces_[s].moving || !surfaces_[s].built) toBuild_.push_back(s);
  tbb::parallel_for(std::size_t(0), toBuild_.size(),
                    [&](std::size_t k) { buildLeaves(input, surfaces_[toBuild_[k]]); });
  stats_.rebuiltSurfaces = toBuild_.size();

  gatherLeaves();
  hashLeaves();
  findLeafPairs(input);
  trianglePairs(input, pairs);
}

void SbhashBroadPhase::syncSurfaces(const BroadPhaseInput& input) {
  // A static surface's leaves are kept as long as it covers the same triangles: the header
  // promises its boxes never change.
  surfaces_.resize(input.surfaces.size());
  for (std::size_t s = 0; s < surfaces_.size(); ++s) {
    SurfaceLeaves& mine = surfaces_[s];
    if (mine.adopt(input.surfaces[s])) mine.boxKnown = mine.built = false;
  }
}

void SbhashBroadPhase::markActiveSurfaces(const BroadPhaseInput& input) {
  tbb::parallel_for(std::size_t(0), surfaces_.size(), [&](std::size_t s) {
    SurfaceLeaves& surface = surfaces_[s];
    if (surface.moving || !surface.boxKnown)
      surface.box = unionOfBoxes(input.triangleBox, surface.firstTriangle,
                                 surface.firstTriangle + surface.triangleCount);
    surface.boxKnown = true;
  });

  // Quadratic in the number of surfaces: scenes have tens of bodies, not thousands.
  activeSurfaces_.clear();
  for (std::size_t s = 0; s < surfaces_.size(); ++s) {
    const SurfaceLeaves& surface = surfaces_[s];
    if (surface.triangleCount == 0) continue;
    bool active = input.surfaces[s].selfCollision;
    for (std::size_t t = 0; t < surfaces_.size() && !active; ++t) {
      const SurfaceLeaves& other = surfaces_[t];
      active = t != s && other.triangleCount > 0 && (surface.moving || other.moving) &&
               surface.box.intersects(other.box);
    }
    if (active) activeSurfaces_.push_back(Index(s));
  }
}

void SbhashBroadPhase::buildLeaves(const BroadPhaseInput& input, SurfaceLeaves& surface) const {
  const int n = 1 << levels_;
  const std::size_t cellCount = std::size_t(n) * n * n;
  for (int axis = 0; axis < 3; ++axis)
    surface.cuts[axis].set(surface.box.min()[axis], surface.box.max()[axis], n);
  const Index first = surface.firstTriangle;

  // Counting sort of (cell, triangle) by cell: one pass counts, one pass places. Each triangle goes
  // to every cell its box reaches, so cells hold whole triangles.
  surface.triangleCells.resize(surface.triangleCount);
  surface.cellStart.assign(cellCount + 1, 0);
  for (Index k = 0; k < surface.triangleCount; ++k) {
    const Box3& box = input.triangleBox[first + k];
    std::array<std::uint8_t, 6>& range = surface.triangleCells[k];
    for (int axis = 0; axis < 3; ++axis) {
      range[2 * axis] = std::uint8_t(surface.cuts[axis].cell(box.min()[axis]));
      range[2 * axis + 1] = std::uint8_t(surface.cuts[axis].cell(box.max()[axis]));
    }
    for (int z = range[4]; z <= range[5]; ++z)
      for (int y = range[2]; y <= range[3]; ++y)
        for (int x = range[0]; x <= range[1]; ++x) ++surface.cellStart[(z * n + y) * n + x + 1];
  }
  for (std::size_t c = 0; c < cellCount; ++c) surface.cellStart[c + 1] += surface.cellStart[c];
  surface.cellFill.assign(surface.cellStart.begin(), surface.cellStart.end() - 1);
  surface.triangles.resize(surface.cellStart[cellCount]);
  for (Index k = 0; k < surface.triangleCount; ++k) {
    const std::array<std::uint8_t, 6>& range = surface.triangleCells[k];
    for (int z = range[4]; z <= range[5]; ++z)
      for (int y = range[2]; y <= range[3]; ++y)
        for (int x = range[0]; x <= range[1]; ++x)
          surface.triangles[surface.cellFill[(z * n + y) * n + x]++] = first + k;
  }

  surface.leaves.clear();
  for (std::size_t c = 0; c < cellCount; ++c) {
    const Index begin = surface.cellStart[c], stop = surface.cellStart[c + 1];
    if (begin == stop) continue;  // empty cells are no leaves
    Box3 box;
    for (Index k = begin; k < stop; ++k) box.extend(input.triangleBox[surface.triangles[k]]);
    const std::array<std::uint8_t, 3> cell = {std::uint8_t(c % n), std::uint8_t(c / n % n),
                                              std::uint8_t(c / (std::size_t(n) * n))};
    for (int axis = 0; axis < 3; ++axis) {
      box.min()[axis] = std::max(box.min()[axis], surface.cuts[axis].cut[cell[axis]]);
      box.max()[axis] = std::min(box.max()[axis], surface.cuts[axis].cut[cell[axis] + 1]);
    }
    surface.leaves.push_back({box, begin, stop, cell});
  }
  surface.built = true;
}

void SbhashBroadPhase::gatherLeaves() {
  leafBox_.clear();
  leafSurface_.clear();
  leafIndex_.clear();
  for (Index s : activeSurfaces_) {
    const std::vector<Leaf>& leaves = surfaces_[s].leaves;
    for (std::size_t l = 0; l < leaves.size(); ++l) {
      leafBox_.push_back(leaves[l].box);
      leafSurface_.push_back(s);
      leafIndex_.push_back(Index(l));
    }
  }
}

void SbhashBroadPhase::hashLeaves() {
  Box3 bounds;
  Vec3d maxExtent = Vec3d::Zero();
  for (const Box3& box : leafBox_) {
    bounds.extend(box);
    maxExtent = maxExtent.cwiseMax(box.max().cast<double>() - box.min().cast<double>());
  }
  grid_ = BoxHashGrid::fit(bounds, maxExtent);

  // A leaf's 8 corners use two cell coordinates per axis; where those are equal, corners share a
  // cell. Count the distinct cells first, to size the table, then reduce hashes to buckets.
  const std::size_t leafCount = leafBox_.size();
  leafBuckets_.resize(leafCount);
  std::size_t entries = 0;
  for (std::size_t l = 0; l < leafCount; ++l) {
    const BoxHashGrid::Cell lo = grid_.cell(leafBox_[l].min()), hi = grid_.cell(leafBox_[l].max());
    const int distinct[3] = {1 + (hi.x() != lo.x()), 1 + (hi.y() != lo.y()),
                             1 + (hi.z() != lo.z())};
    LeafBuckets& mine = leafBuckets_[l];
    mine.count = 0;
    for (int z = 0; z < distinct[2]; ++z)
      for (int y = 0; y < distinct[1]; ++y)
        for (int x = 0; x < distinct[0]; ++x)
          mine.bucket[mine.count++] = BoxHashGrid::hash(
              BoxHashGrid::Cell(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z()));
    entries += mine.count;
  }
  stats_.maxLeafExtent = maxExtent;
  // Load factor ≤ 1/2 over the corner entries; a power of two makes "mod buckets" a mask. The
  // primes are odd, so each axis term still hits every bucket, and a collision only costs a box
  // test, never a pair.
  const std::size_t bucketCount = std::bit_ceil(std::max<std::size_t>(2 * entries, 1));
  const std::uint64_t mask = bucketCount - 1;
  for (LeafBuckets& mine : leafBuckets_) {
    for (std::uint32_t k = 0; k < mine.count; ++k) mine.bucket[k] &= mask;
    std::sort(mine.bucket.begin(), mine.bucket.begin() + mine.count);
    mine.count = std::uint32_t(std::unique(mine.bucket.begin(), mine.bucket.begin() + mine.count) -
                               mine.bucket.begin());
  }

  bucketStart_.assign(bucketCount + 1, 0);
  for (const LeafBuckets& mine : leafBuckets_)
    for (std::uint32_t k = 0; k < mine.count; ++k) ++bucketStart_[mine.bucket[k] + 1];
  for (std::size_t b = 0; b < bucketCount; ++b) bucketStart_[b + 1] += bucketStart_[b];
  bucketFill_.assign(bucketStart_.begin(), bucketStart_.end() - 1);
  bucketLeaves_.resize(bucketStart_[bucketCount]);
  for (std::size_t l = 0; l < leafCount; ++l)
    for (std::uint32_t k = 0; k < leafBuckets_[l].count; ++k)
      bucketLeaves_[bucketFill_[leafBuckets_[l].bucket[k]]++] = Index(l);
}

void SbhashBroadPhase::findLeafPairs(const BroadPhaseInput& input) {
  leafPairs_.clear();
  for (std::size_t l = 0; l < leafBox_.size(); ++l)
    if (input.surfaces[leafSurface_[l]].selfCollision) leafPairs_.push_back({Index(l), Index(l)});

  // A leaf pair sharing several buckets is taken only in the first of them (the bucket lists are
  // sorted), so each pair is listed once without a sort.
  auto firstCommonBucket = [&](Index a, Index b) {
    const LeafBuckets &la = leafBuckets_[a], &lb = leafBuckets_[b];
    std::uint32_t i = 0, j = 0;
    while (la.bucket[i] != lb.bucket[j]) (la.bucket[i] < lb.bucket[j] ? i : j)++;
    return la.bucket[i];  // they share at least the bucket they were found in
  };
  const std::size_t bucketCount = bucketStart_.size() - 1;
  for (std::size_t bucket = 0; bucket < bucketCount; ++bucket) {
    const Index* begin = bucketLeaves_.data() + bucketStart_[bucket];
    const Index* end = bucketLeaves_.data() + bucketStart_[bucket + 1];
    for (const Index* a = begin; a != end; ++a) {
      const Index sa = leafSurface_[*a];
      for (const Index* b = a + 1; b != end; ++b) {
        const Index sb = leafSurface_[*b];
        if (sa == sb) continue;  // step 4 of the file comment
        if (!surfaces_[sa].moving && !surfaces_[sb].moving) continue;
        if (firstCommonBucket(*a, *b) != bucket) continue;
        if (!leafBox_[*a].intersects(leafBox_[*b])) continue;  // a hash collision, or near miss
        leafPairs_.push_back({*a, *b});
      }
    }
  }

  stats_.activeSurfaces = activeSurfaces_.size();
  stats_.leaves = leafBox_.size();
  stats_.buckets = bucketCount;
  stats_.candidateLeafPairs = leafPairs_.size();
  stats_.cellSize = grid_.cellSize;
}

void SbhashBroadPhase::trianglePairs(const BroadPhaseInput& input,
                                     std::vector<TrianglePair>& pairs) {
  const std::size_t chunks = std::min(kMaxChunks, leafPairs_.size());
  const std::size_t perChunk = chunks ? (leafPairs_.size() + chunks - 1) / chunks : 0;
  buffers_.reset(chunks);
  if (nearA_.size() < chunks) nearA_.resize(chunks);
  if (nearB_.size() < chunks) nearB_.resize(chunks);
  // A leaf's near triangles never outnumber the largest leaf: reserved once, no growth inside.
  std::size_t largestLeaf = 0;
  for (const SurfaceLeaves& surface : surfaces_)
    for (const Leaf& leaf : surface.leaves)
      largestLeaf = std::max<std::size_t>(largestLeaf, leaf.end - leaf.begin);
  for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
    nearA_[chunk].reserve(largestLeaf);
    nearB_[chunk].reserve(largestLeaf);
  }
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<TrianglePair>& out = buffers_[chunk];
    std::vector<SweepEntry>&nearA = nearA_[chunk], &nearB = nearB_[chunk];
    const auto byLow = [](const SweepEntry& p, const SweepEntry& q) {
      return p.lo < q.lo || (p.lo == q.lo && p.triangle < q.triangle);
    };
    const auto gather = [&](const SurfaceLeaves& surface, const Leaf& leaf, const Box3* near,
                            std::vector<SweepEntry>& entries) {
      entries.clear();
      for (Index i = leaf.begin; i < leaf.end; ++i) {
        const Index t = surface.triangles[i];
        const Box3& box = input.triangleBox[t];
        if (!near || box.intersects(*near)) entries.push_back({box.min().x(), box.max().x(), t});
      }
      std::sort(entries.begin(), entries.end(), byLow);
    };
    const std::size_t stop = std::min(leafPairs_.size(), (chunk + 1) * perChunk);
    for (std::size_t k = chunk * perChunk; k < stop; ++k) {
      // Not a structured binding: clang before 16 cannot capture one in the lambda below, and
      // the fuzz tree builds with clang 14.
      const Index a = leafPairs_[k][0], b = leafPairs_[k][1];
      const SurfaceLeaves &sa = surfaces_[leafSurface_[a]], &sb = surfaces_[leafSurface_[b]];
      const Leaf &la = sa.leaves[leafIndex_[a]], &lb = sb.leaves[leafIndex_[b]];
      // Step 5 of the file comment: boxes overlap, this leaf pair owns the pair, eligible.
      auto consider = [&](Index i, Index j) {
        const Box3 &bi = input.triangleBox[i], &bj = input.triangleBox[j];
        if (!bi.intersects(bj)) return;
        const Vec3 corner = bi.min().cwiseMax(bj.min());
        if (!sa.owns(la, corner) || (a != b && !sb.owns(lb, corner))) return;
        if (!pairEligible(input, i, j)) return;
        out.push_back(i < j ? TrianglePair{i, j} : TrianglePair{j, i});
      };
      // Sort and sweep on x: only boxes whose x-intervals overlap are compared, so a coarse leaf
      // of many triangles costs about its size, not its size squared.
      if (a == b) {
        gather(sa, la, nullptr, nearA);
        for (std::size_t i = 0; i < nearA.size(); ++i)
          for (std::size_t j = i + 1; j < nearA.size() && nearA[j].lo <= nearA[i].hi; ++j)
            consider(nearA[i].triangle, nearA[j].triangle);
        continue;
      }
      gather(sa, la, &leafBox_[b], nearA);
      if (nearA.empty()) continue;
      gather(sb, lb, &leafBox_[a], nearB);
      std::size_t ia = 0, ib = 0;
      while (ia < nearA.size() && ib < nearB.size()) {
        if (nearA[ia].lo <= nearB[ib].lo) {
          for (std::size_t j = ib; j < nearB.size() && nearB[j].lo <= nearA[ia].hi; ++j)
            consider(nearA[ia].triangle, nearB[j].triangle);
          ++ia;
        } else {
          for (std::size_t i = ia; i < nearA.size() && nearA[i].lo <= nearB[ib].hi; ++i)
            consider(nearA[i].triangle, nearB[ib].triangle);
          ++ib;
        }
      }
    }
  });
  buffers_.mergeInto(pairs);
}

}  // namespace softbake
