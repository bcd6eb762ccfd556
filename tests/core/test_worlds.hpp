#pragma once
// Small worlds for the core tests, built directly so each test controls every number.

#include "core/mesh/icosphere.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/scene/world.hpp"

namespace softbake::test {

/// Two particles of `mass` joined by one spring of rest length 1 along x, no gravity.
inline World springPair(Scalar stiffness, Scalar damping, Scalar mass, Scalar stretchedLength) {
  World world;
  world.settings.gravity.setZero();
  world.position = {Vec3(0, 0, 0), Vec3(stretchedLength, 0, 0)};
  world.previousPosition = world.position;
  world.velocity = {Vec3::Zero(), Vec3::Zero()};
  world.mass = {mass, mass};
  world.inverseMass = {1 / mass, 1 / mass};
  world.particleBody = {0, 0};
  world.springs = {{0, 1, 1, stiffness, damping}};
  world.springRowStart = {0, 1, 2};
  world.springRefs = {0, 1};
  world.triangleRowStart = {0, 0, 0};
  world.springForce.assign(1, Vec3::Zero());
  Body body;
  body.name = "pair";
  body.particleCount = 2;
  body.springCount = 1;
  world.bodies.push_back(body);
  world.bodyVolume = {0};
  world.bodyPressure = {0};
  return world;
}

/// One icosphere body; gravity and ground as given.
inline SceneSetup ballScene(const Material& material, int subdivisions = 3, float radius = 0.5f,
                            Vec3f center = Vec3f(0, 1, 0), bool gravity = true,
                            bool ground = true) {
  SceneSetup scene;
  scene.name = "ball";
  if (!gravity) scene.settings.gravity.setZero();
  BodySetup body;
  body.name = "ball";
  body.mesh = makeIcosphere(subdivisions, radius, center);
  body.material = material;
  body.mass = 1;
  scene.bodies.push_back(body);
  if (ground) scene.planes.push_back(PlaneCollider{});
  return scene;
}

inline Vec3d centroid(const World& world) {
  Vec3d sum = Vec3d::Zero();
  for (const Vec3& p : world.position) sum += p.cast<double>();
  return sum / double(world.particleCount());
}

}  // namespace softbake::test
