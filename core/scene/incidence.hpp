#pragma once
/// Incidence in compressed rows: for each of `count` owners (particles, collision vertices) the
/// references that name it, in item order, so a loop over one owner's rows visits them in a fixed
/// order whatever the thread count.

#include <cstddef>
#include <vector>

#include "core/types.hpp"

namespace softbake {

/// Rows of references per owner: owner o's are refs[rowStart[o] .. rowStart[o + 1]).
/// `visit(item, emit)` calls emit(owner, reference) for each incidence of item. Two passes: count,
/// then fill.
template <class Visit>
void buildIncidence(std::size_t count, std::size_t itemCount, Visit visit,
                    std::vector<Index>& rowStart, std::vector<Index>& refs) {
  rowStart.assign(count + 1, 0);
  for (std::size_t item = 0; item < itemCount; ++item)
    visit(item, [&](Index owner, Index) { ++rowStart[owner + 1]; });
  for (std::size_t o = 0; o < count; ++o) rowStart[o + 1] += rowStart[o];
  refs.resize(rowStart.back());
  std::vector<Index> cursor(rowStart.begin(), rowStart.end() - 1);
  for (std::size_t item = 0; item < itemCount; ++item)
    visit(item, [&](Index owner, Index ref) { refs[cursor[owner]++] = ref; });
}

}  // namespace softbake
