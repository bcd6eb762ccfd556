#pragma once
/// Disjoint sets over indices, kept as parent links in an array the caller owns and reuses (no
/// allocation in a step): what groups the surfaces in contact for "auto" substeps, the failsafe's
/// zones, and the bodies joined by contact springs share.

#include <algorithm>
#include <vector>

namespace softbake {

/// The root of `x`'s set (parent[r] == r), halving the path on the way.
template <class T>
T findRoot(std::vector<T>& parent, T x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

/// Joins the sets of the roots `a` and `b` under the lower of the two, so that the roots do not
/// depend on the order of the joins (the same groups for any thread count); returns it.
template <class T>
T joinRoots(std::vector<T>& parent, T a, T b) {
  const T low = std::min(a, b);
  parent[std::max(a, b)] = low;
  return low;
}

}  // namespace softbake
