#pragma once
/// Two balls (r 0.4 m, 1 280 faces each) of two material presets, the upper one 1 m above the
/// lower, dropped from 5 m onto each other and the ground: the contact sweep's scene
/// (bench/contact_sweep) and the tests of a heavy body landing on a light one.

#include <string>

#include "core/mesh/icosphere.hpp"
#include "core/scene/material.hpp"
#include "core/scene/scene_setup.hpp"

namespace softbake::test {

/// The lower ball weighs 1 kg, the upper one `upperMass` kg.
inline SceneSetup droppedPair(const std::string& lower, const std::string& upper, float upperMass,
                              int frames) {
  SceneSetup scene;
  scene.name = "dropped_pair";
  scene.settings.frames = frames;
  BodySetup bottom;
  bottom.name = "lower";
  bottom.mesh = makeIcosphere(3, 0.4f, Vec3f(0, 5.0f, 0));
  bottom.material = *findMaterialPreset(lower);
  bottom.mass = 1;
  BodySetup top = bottom;
  top.name = "upper";
  // Off the lower ball's axis, so that nothing meets exactly edge on edge.
  top.mesh = makeIcosphere(3, 0.4f, Vec3f(0.05f, 6.0f, 0.03f));
  top.material = *findMaterialPreset(upper);
  top.mass = upperMass;
  scene.bodies = {bottom, top};
  scene.planes.push_back(PlaneCollider{});
  return scene;
}

}  // namespace softbake::test
