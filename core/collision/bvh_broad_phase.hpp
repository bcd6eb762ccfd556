#pragma once
/// An AABB tree per surface ("bvh"): built once by median splits, refitted bottom-up each step,
/// rebuilt when refitting has let it grow loose. Pairs come from descending two trees together
/// (a tree against itself for a self-colliding surface). Output: see
/// core/collision/broad_phase.hpp.

#include <cstdint>
#include <vector>

#include "core/collision/broad_phase.hpp"

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
  BroadPhaseKind kind() const override { return BroadPhaseKind::Bvh; }

  const BvhStats& lastStats() const { return stats_; }

 private:
  struct Node {
    Box3 box;
    Index start = 0;  ///< leaf: first triangle in Tree::order; inner: unused
    Index count = 0;  ///< leaf: triangles (> 0); inner: 0
    Index right = 0;  ///< inner: right child (the left one is the next node)
    bool leaf() const { return count > 0; }
  };

  /// One surface's tree, nodes in depth-first order, so every child comes after its parent.
  struct Tree : broad_phase_detail::CachedSurface {
    bool built = false;
    double looseness = 0;  ///< at the latest build
    std::vector<Node> nodes;
    std::vector<Index> order;  ///< triangle ids, leaf by leaf
    std::vector<Scalar> key;   ///< scratch for the build: centroids along the split axis
  };

  /// Two subtrees to test against each other; the same node twice means "against itself".
  struct Task {
    Index treeA, nodeA, treeB, nodeB;
  };

  static void build(const BroadPhaseInput& input, Tree& tree);
  static Index buildNode(const BroadPhaseInput& input, Tree& tree, Index begin, Index end);
  static double refit(const BroadPhaseInput& input, Tree& tree);
  static double looseness(const Tree& tree);
  bool terminal(const Task& task) const;
  void visit(const BroadPhaseInput& input, const Task& task, std::vector<Task>& more,
             std::vector<TrianglePair>& out) const;

  std::vector<Tree> trees_;
  std::vector<char> rebuilt_;  ///< per tree: built this step
  std::vector<Task> tasks_, nextTasks_;
  std::vector<std::vector<Task>> stacks_;  ///< per chunk
  broad_phase_detail::PairBuffers buffers_;
  BvhStats stats_;
};

}  // namespace softbake
