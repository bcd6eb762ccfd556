// The package consumer (tests/package): a rubber ball built in code, dropped on the ground and
// simulated for a second with softbake::core alone. Prints one line that check_package.cmake
// reads; exits 1 when the ball did not fall or fell through the ground.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <utility>

#include "core/mesh/icosphere.hpp"
#include "core/scene/material.hpp"
#include "core/simulator.hpp"

int main() {
  using namespace softbake;
  SceneSetup setup;
  setup.name = "package_consumer";
  setup.settings.fps = 24;
  setup.settings.frames = 24;
  BodySetup ball;
  ball.name = "ball";
  ball.mesh = makeIcosphere(2, 0.25f, Vec3f(0, 1, 0));
  ball.material = *findMaterialPreset("rubber");
  ball.mass = 1;
  setup.bodies.push_back(std::move(ball));
  setup.planes.push_back(PlaneCollider{});  // the ground, y = 0

  Simulator simulator(buildSceneTopology(setup));
  const auto heights = [&] {
    double sum = 0, lowest = std::numeric_limits<double>::max();
    for (const Vec3& p : simulator.state().position) {
      sum += p.y();
      lowest = std::min(lowest, double(p.y()));
    }
    return std::pair(sum / double(simulator.state().particleCount()), lowest);
  };
  const double start = heights().first;
  for (int frame = 2; frame <= setup.settings.frames; ++frame) simulator.advanceToFrame(frame);
  const auto [centre, lowest] = heights();
  std::printf(
      "softbake package consumer: %zu particles, frame %d, %llu substeps, centre from "
      "%.3f m to %.3f m, lowest point %.4f m\n",
      simulator.state().particleCount(), setup.settings.frames,
      static_cast<unsigned long long>(simulator.stepsTaken()), start, centre, lowest);
  // Free fall alone would take the centre from 1 m to below the ground within the second; the
  // ground must have stopped it above 0, and below where it started.
  if (!(centre < start - 0.3 && lowest > -0.01)) {
    std::fprintf(stderr, "the ball should have fallen onto the ground and stayed on it\n");
    return 1;
  }
  return 0;
}
