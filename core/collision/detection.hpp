#pragma once
/// Detection for one substep (Mesit & Guha §2.1–2.3): broad phase → candidate triangle pairs →
/// the multi-pass line–triangle test on each pair (edge contacts) and on each particle's segment
/// against the triangles its own triangles were paired with (particle contacts).
///
/// Both tests run in one pass over the pairs, which share each pair's normals and corner sides.
/// Every chunk of pairs writes into its own buffers, joined in chunk order, and the results are
/// kept in the broad phase's sorted order, so the output is the same for any thread count and any
/// broad phase. Buffers keep their capacity: a warmed-up substep allocates nothing.

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/broad_phase/pair_cache.hpp"
#include "core/collision/geometry.hpp"
#include "core/collision/initial_overlap.hpp"
#include "core/collision/line_triangle.hpp"
#include "core/collision/triangle_pair_intersection.hpp"
#include "core/parallel.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/stage_timer.hpp"

namespace softbake {

struct CollisionGeometry;
struct SceneTopology;
struct SubstepMotion;

/// An edge of `edgeTriangle` crossing `triangle`.
struct EdgeContact {
  Index edgeTriangle, triangle;
  std::uint8_t edge;  ///< corner `edge` → corner (edge+1)%3 of edgeTriangle
  SegmentTriangleHit hit;
};

/// A particle's motion over the substep crossing `triangle` from its front to its back: from the
/// outside in for a closed surface, from either side for an open one.
struct ParticleContact {
  Index particle, triangle;
  SegmentTriangleHit hit;
  Vec3 normal;  ///< unit normal of the triangle, pointing to the side the particle came from
};

class CollisionDetector {
 public:
  explicit CollisionDetector(const CollisionSettings& settings);

  /// Finds the contacts of the substep that just moved the particles of `topology` from
  /// motion.start to motion.end: refreshes the triangle boxes, runs the broad phase, then the
  /// narrow phase. `clock`, when given, gets a Boxes, a BroadPhase and a NarrowPhase lap.
  void detect(const SceneTopology& topology, const CollisionGeometry& geometry,
              const SubstepMotion& motion, StageClock* clock = nullptr);

  /// Under initial_overlap "ignore": two surfaces (or one with itself) that intersected at the
  /// start never collide with each other; every other pair of surfaces still does.
  void ignoreOverlaps(const InitialOverlaps& overlaps);
  /// Removes from `pairs` (sorted, as every broad phase returns them) those between surfaces that
  /// ignoreOverlaps() made ignore each other, and the pairs set aside (setAside()).
  void dropIgnoredPairs(const CollisionGeometry& geometry, std::vector<TrianglePair>& pairs) const;
  /// dropIgnoredPairs(), and the fitted pairs (setFitted()) too: what detect() keeps.
  void dropLeftAlone(const CollisionGeometry& geometry, std::vector<TrianglePair>& pairs) const;
  /// Triangle pairs that this stage and the failsafe leave alone (initial_overlap "set_aside":
  /// those that intersected at the start, until found apart), sorted. Replaces the previous ones.
  void setAside(std::span<const TrianglePair> pairs) {
    setAside_.assign(pairs.begin(), pairs.end());
  }
  const std::vector<TrianglePair>& setAsidePairs() const { return setAside_; }
  /// Triangle pairs of two surfaces fitted onto each other, closer than the skin where the scene
  /// started and still so: this stage leaves them to the failsafe, which keeps them from crossing
  /// (initial_overlap "set_aside"). Sorted; replaces the previous ones.
  void setFitted(std::span<const TrianglePair> pairs) {
    fitted_.assign(pairs.begin(), pairs.end());
  }
  const std::vector<TrianglePair>& fittedPairs() const { return fitted_; }

  const std::vector<TrianglePair>& candidatePairs() const { return pairs_; }
  /// Sets what candidatePairs() returns until the next detect(): a resumed run's latest substep's
  /// pairs, which "auto" substeps read at the next frame.
  void restoreCandidatePairs(std::span<const TrianglePair> pairs) {
    pairs_.assign(pairs.begin(), pairs.end());
  }
  /// Sorted by candidate pair, then direction and edge.
  const std::vector<EdgeContact>& edgeContacts() const { return edgeContacts_; }
  /// Sorted by particle, then by when the particle crossed (t), then by triangle.
  const std::vector<ParticleContact>& particleContacts() const { return particleContacts_; }
  BroadPhaseKind broadPhase() const { return broadPhase_->kind(); }
  /// The pairs of other boxes of the same triangles (those of a later stage of the substep) from
  /// the pair cache, which takes in the triangles whose boxes left it; false when
  /// settings.collisions.pair_cache is off.
  bool findCachedPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs,
                       std::span<const std::uint8_t> involving = {}) {
    if (!pairCache_) return false;
    pairCache_->findPairs(*broadPhase_, input, pairs, involving);
    return true;
  }
  /// This substep's box of every collision triangle.
  std::span<const Box3> triangleBoxes() const { return boxes_; }
  /// Which self-collision patches, alone and with their neighbours, were flat over this
  /// substep's motion (updateFlatPatches): what the broad phase culled by, for stages that read
  /// its pairs.
  const PatchFlatness& flatPatches() const { return patchFlat_; }

 private:
  void findContacts(const SceneTopology& topology, const CollisionGeometry& geometry,
                    const SubstepMotion& motion);
  /// Where pairs are set aside, the overlap may slide as the bodies deform: a contact whose
  /// triangles (a particle's, for a particle contact) intersected at the substep's start is part
  /// of it, and left alone like the pairs set aside.
  void dropTangledContacts(const SceneTopology& topology, const CollisionGeometry& geometry,
                           const SubstepMotion& motion);

  std::vector<Box3> boxes_;  ///< per collision triangle: static ones fixed, soft ones per substep
  std::vector<Box3> particleBoxes_;  ///< per particle, over the substep: what boxes_ are made of
  PatchFlatness patchFlat_;          ///< the self-collision patches flat over this substep
  std::unique_ptr<BroadPhase> broadPhase_;
  std::optional<PairCache> pairCache_;  ///< unset: the broad phase runs every step
  std::vector<TrianglePair> pairs_;
  std::vector<std::pair<Index, Index>> ignoredSurfaces_;  ///< surface pairs that overlapped, sorted
  std::vector<TrianglePair> setAside_;                    ///< triangle pairs left alone, sorted
  std::vector<TrianglePair> fitted_;         ///< triangle pairs left to the failsafe, sorted
  ChunkBuffers<ParticleContact> chunkHits_;  ///< particle hits, per chunk of pairs
  ChunkBuffers<EdgeContact> chunkEdges_;     ///< edge hits, per chunk of pairs
  std::vector<EdgeContact> edgeContacts_;
  std::vector<ParticleContact> particleContacts_;
};

}  // namespace softbake
