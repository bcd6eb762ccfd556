// One AABB tree per surface rather than one over the scene: a static surface's tree is built once
// and never refitted, surface pairs that may not collide (two static ones) are never descended, and
// each moving tree is refitted on its own, in parallel with the others.
//
// Rebuild rule: a tree's looseness is the summed surface area of its node boxes over the area of
// its root box. Refitting keeps a tree correct but not tight: as triangles move away from the
// neighbours they were grouped with at build, sibling boxes grow into each other and the sum grows
// faster than the root. When the looseness exceeds kRebuildFactor (2) times its value at the
// latest build, the tree is rebuilt. Dividing by the root makes the rule blind to uniform motion
// (a body that translates, or inflates evenly, keeps a good tree), which a rule on the raw sum
// would rebuild for nothing.

#include "core/broad_phase/bvh.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace softbake {

namespace {

/// Enough node pairs to keep any thread count busy, found by descending breadth-first.
constexpr std::size_t kTargetTasks = 256;
constexpr int kMaxExpansionRounds = 32;
constexpr std::size_t kMaxChunks = 256;
/// Triangles per chunk of findPairsInvolving, at least: each descends every tree it may meet.
constexpr std::size_t kQueryGrain = 64;

double area(const Box3& box) {
  if (box.isEmpty()) return 0;
  const Vec3d d = box.max().cast<double>() - box.min().cast<double>();
  return 2 * (d.x() * d.y() + d.y() * d.z() + d.z() * d.x());
}

}  // namespace

void BvhBroadPhase::refitOrRebuild(const BroadPhaseInput& input) {
  rebuilt_.assign(trees_.size(), 0);
  tbb::parallel_for(std::size_t(0), trees_.size(), [&](std::size_t s) {
    Tree& tree = trees_[s];
    if (!tree.built || (tree.moving && refit(input, tree) > kRebuildFactor * tree.looseness)) {
      build(input, tree);
      rebuilt_[s] = 1;
    }
  });
}

void BvhBroadPhase::updateStats() {
  stats_.nodes = 0;
  stats_.rebuilds = 0;
  for (std::size_t s = 0; s < trees_.size(); ++s) {
    stats_.nodes += trees_[s].nodes.size();
    stats_.rebuilds += std::size_t(rebuilt_[s]);
  }
  stats_.totalRebuilds += stats_.rebuilds;
}

void BvhBroadPhase::findPairs(const BroadPhaseInput& input, std::vector<TrianglePair>& pairs) {
  // Trees follow the surfaces; one whose triangles or kind changed is rebuilt.
  trees_.resize(input.surfaces.size());
  for (std::size_t s = 0; s < trees_.size(); ++s) {
    Tree& tree = trees_[s];
    if (tree.adopt(input.surfaces[s])) tree.built = false;
  }
  refitOrRebuild(input);

  tasks_.clear();
  for (Index s = 0; s < trees_.size(); ++s) {
    if (trees_[s].nodes.empty()) continue;
    if (input.surfaces[s].selfCollision) tasks_.push_back({s, 0, s, 0});
    for (Index t = s + 1; t < trees_.size(); ++t)
      if (!trees_[t].nodes.empty() && (trees_[s].moving || trees_[t].moving))
        tasks_.push_back({s, 0, t, 0});
  }
  // Expanding never reaches a leaf pair (those stay tasks), so `pairs` receives nothing here.
  for (int round = 0; round < kMaxExpansionRounds && tasks_.size() < kTargetTasks; ++round) {
    nextTasks_.clear();
    bool expanded = false;
    for (const Task& task : tasks_) {
      if (terminal(task)) {
        nextTasks_.push_back(task);
      } else {
        visit(input, task, nextTasks_, pairs);
        expanded = true;
      }
    }
    tasks_.swap(nextTasks_);
    if (!expanded) break;
  }
  // The two lists trade places each round; with equal capacity, a step with a different number of
  // rounds still finds room in whichever list it ends in.
  const std::size_t capacity = std::max(tasks_.capacity(), nextTasks_.capacity());
  tasks_.reserve(capacity);
  nextTasks_.reserve(capacity);

  const std::size_t chunks = std::min(kMaxChunks, tasks_.size());
  const std::size_t perChunk = chunks ? (tasks_.size() + chunks - 1) / chunks : 0;
  buffers_.reset(chunks);
  if (stacks_.size() < chunks) stacks_.resize(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<Task>& stack = stacks_[chunk];
    stack.clear();
    const std::size_t stop = std::min(tasks_.size(), (chunk + 1) * perChunk);
    for (std::size_t k = chunk * perChunk; k < stop; ++k) {
      stack.push_back(tasks_[k]);
      while (!stack.empty()) {
        const Task task = stack.back();
        stack.pop_back();
        visit(input, task, stack, buffers_[chunk]);
      }
    }
  });
  buffers_.mergeInto(pairs);
  updateStats();
  stats_.tasks = tasks_.size();
}

bool BvhBroadPhase::findPairsInvolving(const BroadPhaseInput& input,
                                       std::span<const Index> triangles,
                                       std::vector<TrianglePair>& pairs) {
  if (trees_.size() != input.surfaces.size()) return false;
  for (std::size_t s = 0; s < trees_.size(); ++s)
    if (!trees_[s].built || !trees_[s].covers(input.surfaces[s])) return false;
  // The triangles ascend, so each surface's are a run; its tree takes them in alone.
  runs_.assign(trees_.size() + 1, triangles.size());
  for (std::size_t k = triangles.size(); k-- > 0;) runs_[input.triangleSurface[triangles[k]]] = k;
  for (std::size_t s = trees_.size(); s-- > 0;) runs_[s] = std::min(runs_[s], runs_[s + 1]);
  rebuilt_.assign(trees_.size(), 0);
  tbb::parallel_for(std::size_t(0), trees_.size(), [&](std::size_t s) {
    if (runs_[s] < runs_[s + 1])
      takeIn(input, triangles.subspan(runs_[s], runs_[s + 1] - runs_[s]), trees_[s], rebuilt_[s]);
  });

  // Chunks by count alone, so the buffers, and the order before the sort, do not depend on the
  // thread count.
  const std::size_t chunks =
      std::min(kMaxChunks, (triangles.size() + kQueryGrain - 1) / kQueryGrain);
  buffers_.reset(chunks);
  if (queryStacks_.size() < chunks) queryStacks_.resize(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::vector<TrianglePair>& out = buffers_[chunk];
    const std::size_t begin = triangles.size() * chunk / chunks;
    const std::size_t end = triangles.size() * (chunk + 1) / chunks;
    // Triangles ascend, so those of one surface come in a run. A tree is descended for the run's
    // triangles only when its root meets the box around all of them: most trees are far away.
    for (std::size_t runStart = begin; runStart < end;) {
      const Index surface = input.triangleSurface[triangles[runStart]];
      std::size_t runEnd = runStart;
      Box3 around;
      for (; runEnd < end && input.triangleSurface[triangles[runEnd]] == surface; ++runEnd)
        around.extend(input.triangleBox[triangles[runEnd]]);
      for (std::size_t s = 0; s < trees_.size(); ++s) {
        const bool mayMeet = s == surface
                                 ? input.surfaces[s].selfCollision
                                 : input.surfaces[s].moving || input.surfaces[surface].moving;
        if (!mayMeet || trees_[s].nodes.empty() || !overlaps(trees_[s].nodes[0].box, around))
          continue;
        for (std::size_t k = runStart; k < runEnd; ++k)
          query(input, triangles[k], trees_[s], queryStacks_[chunk], out);
      }
      runStart = runEnd;
    }
  });
  buffers_.mergeInto(pairs);  // a pair of two given triangles was found from both: once now
  updateStats();
  stats_.tasks = 0;
  return true;
}

void BvhBroadPhase::takeIn(const BroadPhaseInput& input, std::span<const Index> triangles,
                           Tree& tree, char& rebuilt) {
  // A box taken in widens its leaf and the ancestors that do not hold it yet, so the tree stays a
  // true bound. Boxes only grow that way: a tree that has taken in a quarter of its triangles
  // since its latest refit is refitted instead (and rebuilt if that leaves it loose).
  tree.takenIn += Index(triangles.size());
  if (tree.takenIn > tree.triangleCount / 4) {
    if (refit(input, tree) > kRebuildFactor * tree.looseness) {
      build(input, tree);
      rebuilt = 1;
    }
    return;
  }
  for (Index triangle : triangles) {
    const Box3& box = input.triangleBox[triangle];
    for (Index node = tree.leafOf[triangle - tree.firstTriangle];; node = tree.parent[node]) {
      if (tree.nodes[node].box.contains(box)) break;
      tree.nodes[node].box.extend(box);
      if (node == 0) break;
    }
  }
}

void BvhBroadPhase::query(const BroadPhaseInput& input, Index triangle, const Tree& tree,
                          std::vector<Index>& stack, std::vector<TrianglePair>& out) const {
  if (tree.nodes.empty()) return;
  const Box3& box = input.triangleBox[triangle];
  stack.clear();
  stack.push_back(0);
  while (!stack.empty()) {
    const Index n = stack.back();
    stack.pop_back();
    const Node& node = tree.nodes[n];
    if (!overlaps(node.box, box)) continue;
    if (node.leaf()) {
      for (Index k = node.start; k < node.start + node.count; ++k)
        if (tree.order[k] != triangle)
          broad_phase_detail::addIfCandidate(input, triangle, tree.order[k], out);
    } else {
      stack.push_back(node.right);
      stack.push_back(n + 1);
    }
  }
}

void BvhBroadPhase::build(const BroadPhaseInput& input, Tree& tree) {
  tree.nodes.clear();
  tree.order.resize(tree.triangleCount);
  tree.key.resize(tree.triangleCount);
  for (Index k = 0; k < tree.triangleCount; ++k) tree.order[k] = tree.firstTriangle + k;
  tree.parent.clear();
  tree.leafOf.resize(tree.triangleCount);
  tree.takenIn = 0;
  // A self-colliding surface's patches, each kept whole in one subtree while the splits can:
  // then a subtree within a flat patch is skipped whole instead of leaf by leaf.
  tree.patchCentre.clear();
  if (!input.trianglePatch.empty() && tree.triangleCount > 0 &&
      input.trianglePatch[tree.firstTriangle] != ~Index(0)) {
    Index first = ~Index(0), last = 0;
    for (Index t = tree.firstTriangle; t < tree.firstTriangle + tree.triangleCount; ++t) {
      first = std::min(first, input.trianglePatch[t]);
      last = std::max(last, input.trianglePatch[t]);
    }
    if (last != ~Index(0)) {
      tree.firstPatch = first;
      tree.patchCentre.assign(last - first + 1, Vec3::Zero());
      tree.patchSize.assign(tree.patchCentre.size(), 0);
      for (Index t = tree.firstTriangle; t < tree.firstTriangle + tree.triangleCount; ++t) {
        const Index p = input.trianglePatch[t] - first;
        tree.patchCentre[p] += Vec3(input.triangleBox[t].center());
        ++tree.patchSize[p];
      }
      for (std::size_t p = 0; p < tree.patchSize.size(); ++p)
        if (tree.patchSize[p] > 0) tree.patchCentre[p] /= Scalar(tree.patchSize[p]);
    }
  }
  if (tree.triangleCount > 0) buildNode(input, tree, 0, tree.triangleCount, 0);
  tree.looseness = looseness(tree);
  tree.built = true;
}

Index BvhBroadPhase::buildNode(const BroadPhaseInput& input, Tree& tree, Index begin, Index end,
                               Index parent) {
  const Index node = Index(tree.nodes.size());
  tree.nodes.emplace_back();  // children follow: `tree.nodes` may move, so no reference is kept
  tree.parent.push_back(parent);
  Box3 box, centers;
  for (Index k = begin; k < end; ++k) {
    const Box3& triangle = input.triangleBox[tree.order[k]];
    box.extend(triangle);
    centers.extend(Vec3(triangle.center()));
  }
  if (end - begin <= kLeafSize) {
    tree.nodes[node].box = box;
    if (!input.trianglePatch.empty()) {
      Index patch = input.trianglePatch[tree.order[begin]];
      for (Index k = begin + 1; k < end; ++k)
        if (input.trianglePatch[tree.order[k]] != patch) patch = ~Index(0);
      tree.nodes[node].patch = patch;
    }
    tree.nodes[node].start = begin;
    tree.nodes[node].count = end - begin;
    for (Index k = begin; k < end; ++k) tree.leafOf[tree.order[k] - tree.firstTriangle] = node;
    return node;
  }
  // Median split on the longest axis of the centres: halves by count, so the depth is log2(n)
  // whatever the shape, and every level of the tree splits work evenly for the descent. While the
  // range spans several patches, by the patches' centres instead, moved to a patch's boundary.
  const auto patchOf = [&](Index triangle) {
    return tree.patchCentre.empty() ? Index(0) : input.trianglePatch[triangle] - tree.firstPatch;
  };
  bool onePatch = true;
  for (Index k = begin + 1; k < end && onePatch; ++k)
    onePatch = patchOf(tree.order[k]) == patchOf(tree.order[begin]);
  const bool byPatch = !tree.patchCentre.empty() && !onePatch;
  if (byPatch) {
    centers.setEmpty();
    for (Index k = begin; k < end; ++k) centers.extend(tree.patchCentre[patchOf(tree.order[k])]);
  }
  int axis = 0;
  centers.sizes().maxCoeff(&axis);
  for (Index k = begin; k < end; ++k) {
    const Index t = tree.order[k];
    const Scalar c =
        byPatch ? tree.patchCentre[patchOf(t)][axis] : input.triangleBox[t].center()[axis];
    tree.key[t - tree.firstTriangle] = std::isnan(c) ? Scalar(0) : c;  // a strict order
  }
  Index mid = begin + (end - begin) / 2;
  // By patch, ties between patches go by patch, so each patch is one run of the order.
  std::nth_element(tree.order.begin() + begin, tree.order.begin() + mid, tree.order.begin() + end,
                   [&](Index a, Index b) {
                     const Scalar ka = tree.key[a - tree.firstTriangle];
                     const Scalar kb = tree.key[b - tree.firstTriangle];
                     if (ka != kb) return ka < kb;
                     if (byPatch && patchOf(a) != patchOf(b)) return patchOf(a) < patchOf(b);
                     return a < b;
                   });
  if (byPatch) {
    // The patch at the median lies on both sides: its part on the right joins the left.
    const Index straddling = patchOf(tree.order[mid]);
    const auto moved = std::partition(tree.order.begin() + mid, tree.order.begin() + end,
                                      [&](Index t) { return patchOf(t) == straddling; });
    const Index after = Index(moved - tree.order.begin());
    // Unless that leaves the right empty: then the patch goes right whole.
    if (after < end) {
      mid = after;
    } else {
      mid = Index(std::partition(tree.order.begin() + begin, tree.order.begin() + end,
                                 [&](Index t) { return patchOf(t) != straddling; }) -
                  tree.order.begin());
    }
  }
  const Index left = buildNode(input, tree, begin, mid, node);
  const Index right = buildNode(input, tree, mid, end, node);
  tree.nodes[node].box = box;
  tree.nodes[node].right = right;
  if (tree.nodes[left].patch == tree.nodes[right].patch)
    tree.nodes[node].patch = tree.nodes[left].patch;
  return node;
}

double BvhBroadPhase::refit(const BroadPhaseInput& input, Tree& tree) {
  tree.takenIn = 0;
  // Children come after their parent, so one backward sweep sees every child before its parent.
  for (std::size_t n = tree.nodes.size(); n-- > 0;) {
    Node& node = tree.nodes[n];
    if (node.leaf()) {
      node.box.setEmpty();
      for (Index k = node.start; k < node.start + node.count; ++k)
        node.box.extend(input.triangleBox[tree.order[k]]);
    } else {
      node.box = tree.nodes[n + 1].box.merged(tree.nodes[node.right].box);
    }
  }
  return looseness(tree);
}

double BvhBroadPhase::looseness(const Tree& tree) {
  if (tree.nodes.empty()) return 0;
  const double root = area(tree.nodes[0].box);
  if (!(root > 0)) return 0;  // a flat or empty surface: nothing to rebuild for
  double sum = 0;
  for (const Node& node : tree.nodes) sum += area(node.box);
  return sum / root;
}

bool BvhBroadPhase::terminal(const Task& task) const {
  const Node& a = trees_[task.treeA].nodes[task.nodeA];
  const Node& b = trees_[task.treeB].nodes[task.nodeB];
  return a.leaf() && b.leaf();
}

void BvhBroadPhase::visit(const BroadPhaseInput& input, const Task& task, std::vector<Task>& more,
                          std::vector<TrianglePair>& out) const {
  const Tree& ta = trees_[task.treeA];
  const Tree& tb = trees_[task.treeB];
  const Node& a = ta.nodes[task.nodeA];
  const Node& b = tb.nodes[task.nodeB];

  // Two subtrees each within one patch, the same or neighbours, flat as one: no pairs.
  if (task.treeA == task.treeB && input.flatTogether(a.patch, b.patch)) return;
  if (task.treeA == task.treeB && task.nodeA == task.nodeB) {  // a subtree against itself
    if (a.leaf()) {
      for (Index i = a.start; i < a.start + a.count; ++i)
        for (Index j = i + 1; j < a.start + a.count; ++j)
          broad_phase_detail::addIfCandidate(input, ta.order[i], ta.order[j], out);
      return;
    }
    const Index left = task.nodeA + 1, right = a.right;
    more.push_back({task.treeA, left, task.treeA, left});
    more.push_back({task.treeA, right, task.treeA, right});
    if (ta.nodes[left].box.intersects(ta.nodes[right].box))
      more.push_back({task.treeA, left, task.treeA, right});
    return;
  }

  // Callers only hand over pairs whose boxes meet, except the roots of two trees.
  if (!a.box.intersects(b.box)) return;
  if (a.leaf() && b.leaf()) {
    for (Index i = a.start; i < a.start + a.count; ++i)
      for (Index j = b.start; j < b.start + b.count; ++j)
        broad_phase_detail::addIfCandidate(input, ta.order[i], tb.order[j], out);
    return;
  }
  // Descend the larger box, which shrinks the pair's overlap fastest.
  if (b.leaf() || (!a.leaf() && area(a.box) >= area(b.box))) {
    for (Index child : {task.nodeA + 1, a.right})
      if (ta.nodes[child].box.intersects(b.box))
        more.push_back({task.treeA, child, task.treeB, task.nodeB});
  } else {
    for (Index child : {task.nodeB + 1, b.right})
      if (tb.nodes[child].box.intersects(a.box))
        more.push_back({task.treeA, task.nodeA, task.treeB, child});
  }
}

}  // namespace softbake
