#pragma once
/// The per-particle parallel loop of the dynamics stages.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

#include "core/parallel.hpp"
#include "core/types.hpp"

namespace softbake {

/// Runs body(i) for every particle i < count, in parallel. Each call must write only particle
/// i's own entries, so the result does not depend on the thread count.
template <class Body>
void forEachParticle(std::size_t count, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kParticleGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) body(Index(i));
                    });
}

}  // namespace softbake
