// Self-collision on by default (BodySetup::selfCollision unset), for open and closed bodies alike.
// That every example then keeps 0 intersecting pairs within each body on every frame is checked by
// ExampleContacts (example_contacts_test.cpp), which counts a self-colliding body's own pairs.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/simulator.hpp"
#include "importers/scene_file.hpp"
#include "tests/support/intersection_checker.hpp"

namespace softbake {
namespace {

/// An example with every body's self_collision key removed: the default.
SceneSetup exampleByDefault(const std::string& name) {
  SceneSetup scene =
      loadSceneFile(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "examples" / (name + ".json"))
          .setup;
  for (BodySetup& body : scene.bodies) body.selfCollision.reset();
  return scene;
}

TEST(SelfCollision, IsOnByDefaultForOpenAndClosedBodies) {
  for (const char* name : {"flag_fold", "mixed_pile"}) {
    const SceneTopology topology = buildSceneTopology(exampleByDefault(name));
    for (const Body& body : topology.bodies) EXPECT_TRUE(body.selfCollision) << body.name;
  }
}

}  // namespace
}  // namespace softbake
