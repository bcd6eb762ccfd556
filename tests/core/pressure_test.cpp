#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>

#include "core/dynamics/forces.hpp"
#include "core/scene/material.hpp"
#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

double sphereVolume(double r) {
  return 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

TEST(Volume, IcosphereConvergesToTheSphereAtSecondOrder) {
  // An inscribed polyhedron's volume falls short by O(h²): each subdivision halves h, so the
  // error drops about fourfold.
  double previousError = 0;
  for (int level = 2; level <= 5; ++level) {
    Material material;
    test::StagedScene scene(
        buildSceneTopology(test::ballScene(material, level, 1.0f, {0, 0, 0}, false, false)));
    computeVolumes(scene.topology, scene.state, scene.forces);
    const double error = 1 - scene.forces.bodyVolume[0] / sphereVolume(1.0);
    EXPECT_GT(error, 0) << "level " << level << " must be inside the sphere";
    if (level == 4) {
      EXPECT_LT(error, 0.01);
    }
    if (previousError > 0) {
      EXPECT_GT(previousError / error, 3.5) << "level " << level;
      EXPECT_LT(previousError / error, 4.5) << "level " << level;
    }
    previousError = error;
  }
}

TEST(Volume, MatchesTheSerialDoublePrecisionSumAtBuildTime) {
  Material material;
  test::StagedScene scene(
      buildSceneTopology(test::ballScene(material, 4, 0.7f, {3, -2, 5}, false, false)));
  const double atBuild = scene.topology.bodies[0].restVolume;
  computeVolumes(scene.topology, scene.state, scene.forces);
  EXPECT_NEAR(scene.forces.bodyVolume[0], atBuild, 1e-12 * atBuild);
}

TEST(Pressure, ForcesOnAClosedBodySumToZero) {
  Material material;
  material.pressure = 500;
  test::StagedScene scene(
      buildSceneTopology(test::ballScene(material, 4, 0.5f, {0, 0, 0}, false, false)));
  computeVolumes(scene.topology, scene.state, scene.forces);
  computePressureForces(scene.topology, scene.state, scene.forces);
  Vec3d sum = Vec3d::Zero();
  double magnitude = 0;
  for (const Vec3& f : scene.forces.triangleForce) {
    sum += 3 * f.cast<double>();
    magnitude += 3 * f.cast<double>().norm();
  }
  EXPECT_LT(sum.norm(), 1e-5 * magnitude);
  // And the total outward push is P·(surface area).
  EXPECT_NEAR(magnitude, 500.0 * 4 * std::numbers::pi * 0.25, 0.02 * magnitude);
}

TEST(Pressure, IsIdealGasOfTheCurrentVolume) {
  Material material;
  material.pressure = 200;
  material.bulkModulus = 0;  // the gas law alone
  test::StagedScene scene(
      buildSceneTopology(test::ballScene(material, 3, 0.5f, {0, 0, 0}, false, false)));
  for (Vec3& p : scene.state.position) p *= 2;  // eight times the volume
  computeVolumes(scene.topology, scene.state, scene.forces);
  computePressureForces(scene.topology, scene.state, scene.forces);
  EXPECT_NEAR(scene.forces.bodyPressure[0], 200.0 / 8, 1e-3);
}

TEST(Pressure, OpenMeshHasNoPressure) {
  Material material;
  material.pressure = 500;
  SceneSetup scene = test::ballScene(material, 2, 0.5f, {0, 0, 0}, false, false);
  scene.bodies[0].mesh.triangles.pop_back();
  BuildReport report;
  const SceneTopology topology = buildSceneTopology(scene, &report);
  EXPECT_FALSE(topology.bodies[0].closed);
  EXPECT_EQ(topology.bodies[0].gasAmount, 0);
  ASSERT_EQ(report.notes.size(), 1u);
  EXPECT_NE(report.notes[0].find("pressure is off"), std::string::npos) << report.notes[0];
}

/// A box of eight corners: a quad 1 m by 2 cm in the plane y = 1, and the same quad moved by
/// `offset`; closed and consistently wound whatever the offset. Moved within the plane, every
/// corner lies in it, as the flat trim pieces of CAD exports do (assimp's test corpus,
/// OBJ/regr01.obj, 'Valm-kant', whose faces these are).
SceneSetup slabScene(const Vec3f& offset) {
  SceneSetup scene;
  scene.name = "slab";
  BodySetup body;
  body.name = "slab";
  body.material = *findMaterialPreset("rubber");
  body.mass = 1;
  const std::array<Vec3f, 4> quad = {Vec3f(0.5f, 1, 0.01f), Vec3f(0.49f, 1, -0.01f),
                                     Vec3f(-0.49f, 1, -0.01f), Vec3f(-0.5f, 1, 0.01f)};
  for (const Vec3f& p : quad) body.mesh.positions.push_back(p);
  for (const Vec3f& p : quad) body.mesh.positions.push_back(p + offset);
  body.mesh.triangles = {{0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6},
                         {3, 0, 4}, {3, 4, 7}, {2, 0, 3}, {1, 0, 2}, {6, 7, 4}, {5, 6, 4}};
  scene.bodies.push_back(body);
  scene.planes.push_back(PlaneCollider{});
  return scene;
}

TEST(Pressure, AClosedBoxFoldedFlatIsOpenAndFallsWithoutBlowingUp) {
  // Two float steps off the plane: not exactly flat, as the corpus file's piece is not.
  SceneSetup flat = slabScene(Vec3f(0, 2.4e-7f, 0.01f));
  ASSERT_GT(flat.bodies[0].material.pressure, 0);
  ASSERT_GT(flat.bodies[0].material.bulkModulus, 0);
  flat.settings.frames = 24;
  BuildReport report;
  const SceneTopology topology = buildSceneTopology(flat, &report);
  // Its rest volume is float rounding, which the bulk term's K/V_rest turned into forces without
  // bound: the corpus file blew up in its second frame.
  Simulator simulator{SceneTopology(topology)};
  for (int frame = 2; frame <= 24; ++frame) ASSERT_NO_THROW(simulator.advanceToFrame(frame));
  for (const Vec3& v : simulator.state().velocity) EXPECT_LT(v.norm(), 5.0f);
  EXPECT_FALSE(topology.bodies[0].closed);
  EXPECT_EQ(topology.bodies[0].gasAmount, 0);
  ASSERT_EQ(report.notes.size(), 1u);
  EXPECT_NE(report.notes[0].find("closed but flat"), std::string::npos) << report.notes[0];
}

TEST(Pressure, AThinButRealSlabStaysClosed) {
  // 1 mm deep: its volume is 2e-3 of its area^(3/2), two thousand times the bound.
  const SceneTopology topology = buildSceneTopology(slabScene(Vec3f(0, 0.001f, 0)));
  EXPECT_TRUE(topology.bodies[0].closed);
  EXPECT_GT(topology.bodies[0].gasAmount, 0);
}

// Independent reference: restrict the body to uniform scalings x → λx. Spring energy is
// Σ ½k(λ−1)²L², gas energy −nRT·ln V with V ∝ λ³. Stationary when λ(λ−1)·Σ kL² = 3nRT.
double uniformScalingEquilibrium(const SceneTopology& topology) {
  double stiffnessLengthSquared = 0;
  for (const Spring& s : topology.springs)
    stiffnessLengthSquared += double(s.stiffness) * s.restLength * s.restLength;
  const double c = 3 * topology.bodies[0].gasAmount / stiffnessLengthSquared;
  return (1 + std::sqrt(1 + 4 * c)) / 2;
}

TEST(Pressure, BalloonInflatesToTheIdealGasEquilibrium) {
  Material balloon = *findMaterialPreset("balloon");
  balloon.damping = 0.3f;  // settle within the test's few simulated seconds
  Simulator simulator(
      buildSceneTopology(test::ballScene(balloon, 3, 0.5f, {0, 0, 0}, false, false)));
  const double lambda = uniformScalingEquilibrium(simulator.topology());
  ASSERT_GT(lambda, 1.1) << "the balloon preset should visibly inflate";
  const double expectedVolume =
      simulator.topology().bodies[0].restVolume * lambda * lambda * lambda;
  for (int frame = 2; frame <= 24 * 6; ++frame) simulator.advanceToFrame(frame);
  const SimulationState& end = simulator.state();
  ForceBuffers forces(simulator.topology());
  computeVolumes(simulator.topology(), end, forces);
  EXPECT_NEAR(forces.bodyVolume[0] / expectedVolume, 1.0, 0.03)
      << "λ=" << lambda << " volume " << forces.bodyVolume[0] << " expected " << expectedVolume;
  // Settled: the membrane no longer moves.
  double maxSpeed = 0;
  for (const Vec3& v : end.velocity) maxSpeed = std::max(maxSpeed, double(v.norm()));
  EXPECT_LT(maxSpeed, 0.01);
}

}  // namespace
}  // namespace softbake
