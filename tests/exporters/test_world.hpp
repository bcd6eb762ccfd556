#pragma once
/// Scenes and scratch directories shared by the exporter tests.

#include <string>
#include <vector>

#include "core/mesh/icosphere.hpp"
#include "core/scene/world.hpp"
#include "tests/support/scratch_directory.hpp"

namespace softbake::test {

/// One icosphere per radius, side by side, named "ball0", "ball1", ...
inline World makeBallsWorld(std::vector<float> radii, int subdivisions = 2) {
  SceneSetup setup;
  setup.name = "balls";
  for (std::size_t i = 0; i < radii.size(); ++i) {
    BodySetup body;
    body.name = "ball" + std::to_string(i);
    body.mesh = makeIcosphere(subdivisions, radii[i], Vec3f(3.0f * float(i), 1, 0));
    setup.bodies.push_back(std::move(body));
  }
  return buildWorld(setup);
}

}  // namespace softbake::test
