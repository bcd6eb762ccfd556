// Two balls (r 0.4 m) of every pair of material presets, dropped from 5 m onto each other and the
// ground at upper:lower mass ratios of 1:100, 1:10, 1:1, 10:1 and 100:1, under the default
// settings: whether the run reaches its last frame (72), the most intersecting triangle pairs
// between the two at the end of a frame, by the tests' exact checker, and the most the total
// energy rose above its start at the end of a frame. One markdown table; bench/contacts.sh runs it.
#include <algorithm>
#include <cstdio>
#include <string>

#include "core/dynamics/energy.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "tests/support/dropped_pair.hpp"
#include "tests/support/intersection_checker.hpp"

using namespace softbake;

namespace {
constexpr int kFrames = 72;

std::string run(const char* lower, const char* upper, float ratio) {
  Simulator simulator(buildSceneTopology(test::droppedPair(lower, upper, ratio, kFrames)));
  const double start = computeEnergy(simulator.topology(), simulator.state()).total();
  double rise = 0;
  std::size_t worst = 0;
  for (int frame = 2; frame <= kFrames; ++frame) {
    try {
      simulator.advanceToFrame(frame);
    } catch (const Error&) {
      return "blew up at " + std::to_string(frame);
    }
    worst = std::max(worst,
                     test::countIntersectingPairs(simulator.collision(), simulator.state().position)
                         .betweenSurfaces);
    rise = std::max(rise, computeEnergy(simulator.topology(), simulator.state()).total() - start);
  }
  char cell[64];
  std::snprintf(cell, sizeof cell, "%zu, %+.2f J", worst, rise);
  return cell;
}
}  // namespace

int main() {
  const char* presets[] = {"stiff", "rubber", "jelly", "balloon"};
  std::printf(
      "| lower | upper | 1:100 | 1:10 | 1:1 | 10:1 | 100:1 "
      "|\n|---|---|---:|---:|---:|---:|---:|\n");
  for (const char* lower : presets)
    for (const char* upper : presets) {
      std::printf("| %s | %s", lower, upper);
      for (float ratio : {0.01f, 0.1f, 1.0f, 10.0f, 100.0f})
        std::printf(" | %s", run(lower, upper, ratio).c_str());
      std::printf(" |\n");
      std::fflush(stdout);
    }
  return 0;
}
