#pragma once
/// The broad phases' contract written out as the slowest possible loop, for tests to compare
/// every broad phase (and the pair cache) with.

#include <vector>

#include "core/broad_phase/broad_phase.hpp"

namespace softbake::test {

/// Every i < j with overlapping boxes that pairEligible allows, in order.
inline std::vector<TrianglePair> definitionPairs(const BroadPhaseInput& input) {
  std::vector<TrianglePair> pairs;
  for (Index i = 0; i < input.triangleBox.size(); ++i)
    for (Index j = i + 1; j < input.triangleBox.size(); ++j)
      if (input.triangleBox[i].intersects(input.triangleBox[j]) && pairEligible(input, i, j))
        pairs.push_back({i, j});
  return pairs;
}

}  // namespace softbake::test
