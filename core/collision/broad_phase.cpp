#include "core/collision/broad_phase.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>

#include "core/collision/bvh_broad_phase.hpp"
#include "core/collision/sbhash_broad_phase.hpp"
#include "core/collision/spatial_hash_broad_phase.hpp"
#include "core/enum_names.hpp"

namespace softbake {

bool pairEligible(const BroadPhaseInput& input, Index i, Index j) {
  const Index si = input.triangleSurface[i], sj = input.triangleSurface[j];
  if (si != sj) return input.surfaces[si].moving || input.surfaces[sj].moving;
  if (!input.surfaces[si].selfCollision) return false;
  // Triangles sharing a vertex always touch at it: that contact is the mesh itself, not a
  // collision, so it never reaches the narrow phase.
  for (Index a : input.triangleVertices[i])
    for (Index b : input.triangleVertices[j])
      if (a == b) return false;
  return true;
}

std::string_view broadPhaseName(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::Sbhash:
      return "sbhash";
    case BroadPhaseKind::SpatialHash:
      return "spatialhash";
    case BroadPhaseKind::Bvh:
      return "bvh";
    case BroadPhaseKind::BruteForce:
      return "brute";
  }
  return "unknown";
}

std::vector<std::string> broadPhaseNames() {
  return namesOf(std::span<const BroadPhaseKind>(kBroadPhaseKinds), broadPhaseName);
}

bool parseBroadPhase(std::string_view name, BroadPhaseKind& kind) {
  return parseNamed(name, std::span<const BroadPhaseKind>(kBroadPhaseKinds), broadPhaseName, kind);
}

namespace broad_phase_detail {

void sortUnique(std::vector<TrianglePair>& pairs, std::vector<TrianglePair>& scratch) {
  // Key: first · 2³² + second. Bytes that are zero in every key are skipped: a pass over them
  // would keep the order.
  std::uint32_t usedBits[2] = {0, 0};
  for (const TrianglePair& pair : pairs) usedBits[0] |= pair.second, usedBits[1] |= pair.first;
  scratch.resize(pairs.size());
  for (int pass = 0; pass < 8; ++pass) {
    const int half = pass / 4, shift = 8 * (pass % 4);
    if (((usedBits[half] >> shift) & 0xff) == 0) continue;
    const auto digit = [&](const TrianglePair& pair) {
      return ((half ? pair.first : pair.second) >> shift) & 0xff;
    };
    std::array<std::size_t, 257> start{};
    for (const TrianglePair& pair : pairs) ++start[digit(pair) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (const TrianglePair& pair : pairs) scratch[start[digit(pair)]++] = pair;
    pairs.swap(scratch);
  }
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

void PairBuffers::reset(std::size_t chunks) {
  // Never shrinks: the buffers of the chunks unused this step keep their capacity for the next.
  if (buffers_.size() < chunks) buffers_.resize(chunks);
  for (std::vector<TrianglePair>& buffer : buffers_) buffer.clear();
}

void PairBuffers::mergeInto(std::vector<TrianglePair>& pairs) {
  pairs.clear();
  for (const std::vector<TrianglePair>& buffer : buffers_)
    pairs.insert(pairs.end(), buffer.begin(), buffer.end());
  sortUnique(pairs, scratch_);
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
