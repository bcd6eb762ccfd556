#pragma once
/// An AABB tree per surface ("bvh"): built once by median splits, refitted bottom-up each step,
/// rebuilt when refitting has let it grow loose. Pairs come from descending two trees together
/// (a tree against itself for a self-colliding surface). Output: see
/// core/broad_phase/broad_phase.hpp.

#include <cstdint>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"

namespace softbake {

/// What the latest findPairs saw, for tests and tuning.
struct BvhStats {
  std::size_t nodes = 0;          ///< in all trees
  std::size_t rebuilds = 0;       ///< trees built this step (first step: all of them)
  std::size_t totalRebuilds = 0;  ///< since construction
  std::size_t tasks = 0;          ///< node pairs handed to the parallel descent
};

class BvhBroadPhase final : public BroadPhase {
 public:
  /// Triangles per leaf: below this, box tests are cheaper than another level of nodes.
  static constexpr Index kLeafSize = 4;
  /// A tree is rebuilt once its looseness (see the .cpp) exceeds this factor of its value at build.
  static constexpr double kRebuildFactor = 2;

  void findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) override;
  /// Refits the trees (rebuilding loose ones, as findPairs does), then descends every tree the
  /// triangle may meet with each given triangle's box.
  bool findPairsInvolving(const BroadPhaseInput& input, std::span<const Index> triangles,
                          std::vector<TrianglePair>& pairs) override;
  BroadPhaseKind kind() const override { return BroadPhaseKind::Bvh; }

  const BvhStats& lastStats() const { return stats_; }

 private:
  struct Node {
    Box3 box;
    Index start = 0;  ///< leaf: first triangle in Tree::order; inner: unused
    Index count = 0;  ///< leaf: triangles (> 0); inner: 0
    Index right = 0;  ///< inner: right child (the left one is the next node)
    /// The self-collision patch all its triangles lie in, or none (~0): a subtree within one
    /// patch that is flat this step has no pairs within itself.
    Index patch = ~Index(0);
    bool leaf() const { return count > 0; }
  };

  /// One surface's tree, nodes in depth-first order, so every child comes after its parent.
  struct Tree : broad_phase_detail::CachedSurface {
    bool built = false;
    double looseness = 0;  ///< at the latest build
    std::vector<Node> nodes;
    std::vector<Index> order;  ///< triangle ids, leaf by leaf
    std::vector<Scalar> key;   ///< scratch for the build: centroids along the split axis
    /// Scratch for the build: per self-collision patch of the surface (numbered from its first),
    /// the mean of its triangles' box centres.
    std::vector<Vec3> patchCentre;
    std::vector<Index> patchSize;  ///< scratch for the build: the patches' triangle counts
    Index firstPatch = 0;
    std::vector<Index> parent;  ///< per node (the root's is itself)
    std::vector<Index> leafOf;  ///< per triangle of the surface: its leaf
    /// Triangles whose boxes were taken in along their leaf's path since the latest refit.
    Index takenIn = 0;
  };

  /// Two subtrees to test against each other; the same node twice means "against itself".
  struct Task {
    Index treeA, nodeA, treeB, nodeB;
  };

  /// Builds the trees not built yet, refits the moving ones and rebuilds those grown loose.
  void refitOrRebuild(const BroadPhaseInput& input);
  /// Makes `tree` hold the new boxes of `triangles` (its own, ascending).
  void takeIn(const BroadPhaseInput& input, std::span<const Index> triangles, Tree& tree,
              char& rebuilt);
  void updateStats();
  /// Appends the pairs of `triangle` with the triangles of `tree` whose boxes meet its box.
  void query(const BroadPhaseInput& input, Index triangle, const Tree& tree,
             std::vector<Index>& stack, std::vector<TrianglePair>& out) const;
  static void build(const BroadPhaseInput& input, Tree& tree);
  static Index buildNode(const BroadPhaseInput& input, Tree& tree, Index begin, Index end,
                         Index parent);
  static double refit(const BroadPhaseInput& input, Tree& tree);
  static double looseness(const Tree& tree);
  bool terminal(const Task& task) const;
  void visit(const BroadPhaseInput& input, const Task& task, std::vector<Task>& more,
             std::vector<TrianglePair>& out) const;

  std::vector<Tree> trees_;
  std::vector<char> rebuilt_;  ///< per tree: built this step
  std::vector<Task> tasks_, nextTasks_;
  std::vector<std::vector<Task>> stacks_;        ///< per chunk
  std::vector<std::vector<Index>> queryStacks_;  ///< per chunk of findPairsInvolving
  std::vector<std::size_t> runs_;                ///< findPairsInvolving: where each surface's begin
  broad_phase_detail::PairBuffers buffers_;
  BvhStats stats_;
};

}  // namespace softbake
