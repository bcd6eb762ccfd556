#pragma once
// Small scenes for the core tests, built directly so each test controls every number.

#include <vector>

#include "core/collision/geometry.hpp"
#include "core/dynamics/forces.hpp"
#include "core/dynamics/integrator.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake::test {

/// A topology, its state and the stages' buffers, for tests that run one stage at a time.
struct StagedScene {
  SceneTopology topology;
  CollisionGeometry collision;
  SimulationState state;
  ForceBuffers forces;
  std::vector<Vec3> substepStart;  ///< the integrator's copy of where the substep began

  explicit StagedScene(SceneTopology built)
      : topology(std::move(built)),
        collision(buildCollisionGeometry(topology)),
        state(initialState(topology)),
        forces(topology),
        substepStart(state.position) {}
};

/// Two particles of `mass` joined by one spring of rest length 1 along x, no gravity.
inline StagedScene springPair(Scalar stiffness, Scalar damping, Scalar mass,
                              Scalar stretchedLength) {
  SceneTopology topology;
  topology.settings.gravity.setZero();
  topology.restPosition = {Vec3(0, 0, 0), Vec3(stretchedLength, 0, 0)};
  topology.mass = {mass, mass};
  topology.inverseMass = {1 / mass, 1 / mass};
  topology.particleBody = {0, 0};
  topology.springs = {{0, 1, 1, stiffness, damping}};
  topology.springRowStart = {0, 1, 2};
  topology.springRefs = {0, 1};
  topology.triangleRowStart = {0, 0, 0};
  Body body;
  body.name = "pair";
  body.particleCount = 2;
  body.springCount = 1;
  topology.bodies.push_back(body);
  return StagedScene(std::move(topology));
}

/// The pair's one substep without pressure: springs, then the integrator.
inline bool springStep(StagedScene& scene, Scalar dt) {
  computeSpringForces(scene.topology, scene.state, scene.forces);
  return integrate(scene.topology, scene.forces, dt, scene.state, scene.substepStart);
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

/// Two icosphere balls of radius 0.4 at x = ±0.6, 2 m up, named "left" and "right", with their own
/// velocities; no gravity change, no ground.
inline SceneSetup twoBallsOnX(const Material& material, const Vec3& leftVelocity,
                              const Vec3& rightVelocity) {
  SceneSetup scene;
  for (float x : {-0.6f, 0.6f}) {
    BodySetup body;
    body.name = x < 0 ? "left" : "right";
    body.mesh = makeIcosphere(3, 0.4f, Vec3f(x, 2, 0));
    body.material = material;
    body.velocity = x < 0 ? leftVelocity : rightVelocity;
    scene.bodies.push_back(body);
  }
  return scene;
}

inline Vec3d centroid(const SimulationState& state) {
  Vec3d sum = Vec3d::Zero();
  for (const Vec3& p : state.position) sum += p.cast<double>();
  return sum / double(state.particleCount());
}

}  // namespace softbake::test
