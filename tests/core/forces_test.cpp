#include "core/dynamics/forces.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/scene/material.hpp"
#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

TEST(SpringForce, StretchedSpringPullsBackWithHookesLaw) {
  test::StagedScene pair =
      test::springPair(/*stiffness=*/100, /*damping=*/0, /*mass=*/1, /*length=*/1.5f);
  computeSpringForces(pair.topology, pair.state, pair.forces);
  // |f| = k·(L − L0) = 100·0.5, pulling a towards b (+x) and b towards a.
  EXPECT_NEAR(pair.forces.springForce[0].x(), 50.0, 1e-4);
  EXPECT_NEAR(pair.forces.springForce[0].y(), 0.0, 1e-6);
  EXPECT_NEAR(pair.forces.springForce[0].z(), 0.0, 1e-6);
}

TEST(SpringForce, CompressedSpringPushesApart) {
  test::StagedScene pair = test::springPair(100, 0, 1, 0.75f);
  computeSpringForces(pair.topology, pair.state, pair.forces);
  EXPECT_NEAR(pair.forces.springForce[0].x(), -25.0, 1e-4);
}

TEST(SpringForce, DampingActsOnRelativeVelocityAlongTheAxisOnly) {
  test::StagedScene pair = test::springPair(100, /*damping=*/2, 1, /*length=*/1);
  pair.state.velocity[1] = Vec3(3, 5, 0);  // separating at 3 m/s, sliding sideways at 5 m/s
  computeSpringForces(pair.topology, pair.state, pair.forces);
  EXPECT_NEAR(pair.forces.springForce[0].x(), 2 * 3.0, 1e-5);
  EXPECT_NEAR(pair.forces.springForce[0].y(), 0.0, 1e-6);
}

TEST(SpringForce, BodyAtRestStaysAtRest) {
  Material material;
  material.pressure = 0;
  Simulator simulator(buildSceneTopology(test::ballScene(material, 3, 0.5f, {0, 1, 0},
                                                         /*gravity=*/false, /*ground=*/false)));
  const std::vector<Vec3> start = simulator.state().position;
  for (int frame = 2; frame <= 10; ++frame) simulator.advanceToFrame(frame);
  const SimulationState& end = simulator.state();
  for (Index i = 0; i < end.particleCount(); ++i) {
    EXPECT_EQ(end.position[i], start[i]) << "particle " << i;
    EXPECT_EQ(end.velocity[i], Vec3::Zero()) << "particle " << i;
  }
}

TEST(Mass, SpreadByVertexAreaAndSumsToBodyMass) {
  Material material;
  SceneSetup scene = test::ballScene(material);
  scene.bodies[0].mass = 2.5f;
  const SceneTopology topology = buildSceneTopology(scene);
  double total = 0;
  for (Scalar m : topology.mass) total += m;
  EXPECT_NEAR(total, 2.5, 1e-5);
  // Icosphere vertices have unequal areas (the 12 original vertices have five neighbours), so
  // area weighting must give unequal masses; an even split would not.
  const auto [lightest, heaviest] = std::minmax_element(topology.mass.begin(), topology.mass.end());
  EXPECT_LT(*lightest, *heaviest * 0.95f);
}

TEST(Pins, PinnedParticlesDoNotMoveUnderGravityUnderEitherIntegrator) {
  for (IntegratorKind integrator : kIntegratorKinds) {
    Material material;
    material.pressure = 0;
    SceneSetup scene = test::ballScene(material, 2, 0.5f, {0, 1, 0}, true, false);
    scene.bodies[0].pins.boxes.push_back({Vec3f(-1, 1.4f, -1), Vec3f(1, 2, 1)});  // the top cap
    scene.bodies[0].pins.particles.push_back(0);
    scene.settings.integrator = integrator;
    Simulator simulator(buildSceneTopology(scene));
    std::vector<Index> pinned;
    for (Index i = 0; i < simulator.topology().particleCount(); ++i)
      if (simulator.topology().inverseMass[i] == 0) pinned.push_back(i);
    ASSERT_GT(pinned.size(), 3u);
    const std::vector<Vec3> start = simulator.state().position;
    for (int frame = 2; frame <= 24; ++frame) simulator.advanceToFrame(frame);
    for (Index i : pinned)
      EXPECT_EQ(simulator.state().position[i], start[i]) << integratorName(integrator);
    // The rest hangs: after a second the centroid has sagged by 2.2 mm (implicit), 2.3 (XPBD) or
    // 2.7 (explicit); at rest it would be at 1 to float precision.
    const double sag = 1.0 - test::centroid(simulator.state()).y();
    RecordProperty(std::string("sag_") + std::string(integratorName(integrator)),
                   std::to_string(sag));
    EXPECT_GT(sag, 0.0018) << integratorName(integrator);
    EXPECT_LT(sag, 0.0033) << integratorName(integrator);
  }
}

TEST(Pins, IndexBeyondTheBodyIsAnErrorNamingIt) {
  Material material;
  SceneSetup scene = test::ballScene(material, 1);
  scene.bodies[0].pins.particles.push_back(9999);
  try {
    buildSceneTopology(scene);
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("body 'ball': pin index 9999"), std::string::npos)
        << e.what();
  }
}

TEST(Pins, AVertexPinsTheParticleItWeldsInto) {
  // Two triangles sharing an edge whose corners are listed twice (a UV seam): render vertices
  // 3 and 4 weld into the particles of 0 and 2.
  SceneSetup scene;
  BodySetup& body = scene.bodies.emplace_back();
  body.name = "sheet";
  body.mesh.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(1, 0, 1),
                         Vec3f(0, 0, 0), Vec3f(1, 0, 1), Vec3f(0, 0, 1)};
  body.mesh.triangles = {{0, 2, 1}, {3, 5, 4}};
  body.pins.vertices = {4};
  const SceneTopology topology = buildSceneTopology(scene);
  ASSERT_EQ(topology.particleCount(), 4u);
  std::vector<Vec3> pinned;
  for (std::size_t i = 0; i < topology.particleCount(); ++i)
    if (topology.inverseMass[i] == 0) pinned.push_back(topology.restPosition[i]);
  EXPECT_EQ(pinned, (std::vector<Vec3>{Vec3(1, 0, 1)}));

  body.pins.vertices = {6};
  try {
    buildSceneTopology(scene);
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_EQ(std::string(e.what()), "body 'sheet': pinned vertex 6 is beyond its 6 vertices");
  }
}

/// The height of a ball's top after it has sat on the ground for two seconds: an icosphere of
/// radius 0.3 m with the rubber preset's springs but neither gas nor bulk term, so that only its
/// springs hold it up, and the bend stiffness given. Scene defaults otherwise (implicit, auto).
double emptyBallHeight(Scalar bendStiffness) {
  Material material = *findMaterialPreset("rubber");
  material.pressure = 0;
  material.bulkModulus = 0;
  material.bendStiffness = bendStiffness;
  SceneSetup scene = test::ballScene(material, 3, 0.3f, Vec3f(0, 0.301f, 0));
  scene.settings.frames = 48;
  Simulator simulator(buildSceneTopology(scene));
  for (int frame = 2; frame <= scene.settings.frames; ++frame) simulator.advanceToFrame(frame);
  Scalar top = 0;
  for (const Vec3& x : simulator.state().position) top = std::max(top, x.y());
  return top;
}

TEST(BendStiffness, HoldsUpABallWithoutGasAndMoreOfItHoldsItHigher) {
  // Without gas the structural springs alone hold a ball up, and they give: it slumps on the
  // ground. The bending springs across its edges hold its curvature; the stiffer, the higher it
  // stands, up to its rest height of 0.6 m. Nothing else differs between the three. Measured:
  // 0.41, 0.56 and 0.59 m.
  const double none = emptyBallHeight(0);
  const double rubber = emptyBallHeight(300);
  const double stiff = emptyBallHeight(3000);
  EXPECT_GT(rubber, none + 0.02);
  EXPECT_GT(stiff, rubber + 0.01);
  EXPECT_LE(stiff, 0.6 + 0.01) << "nothing lifts it above its rest height";
}

}  // namespace
}  // namespace softbake
