#pragma once
/// Scenes and scratch directories shared by the exporter tests.

#include <string>
#include <vector>

#include <memory>
#include "core/mesh/icosphere.hpp"

#include "core/scene/scene_topology.hpp"
#include "tests/support/scratch_directory.hpp"

namespace softbake::test {

/// One icosphere per radius, side by side, named "ball0", "ball1", ...
inline std::shared_ptr<const SceneTopology> makeBallsTopology(std::vector<float> radii,
                                                              int subdivisions = 2) {
  SceneSetup setup;
  setup.name = "balls";
  for (std::size_t i = 0; i < radii.size(); ++i) {
    BodySetup body;
    body.name = "ball" + std::to_string(i);
    body.mesh = makeIcosphere(subdivisions, radii[i], Vec3f(3.0f * float(i), 1, 0));
    setup.bodies.push_back(std::move(body));
  }
  return std::make_shared<const SceneTopology>(buildSceneTopology(setup));
}

}  // namespace softbake::test
