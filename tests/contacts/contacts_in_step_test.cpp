// Contacts kept apart inside the implicit step (core/dynamics/contact_springs.hpp,
// core/collision/step_contacts.hpp): large steps stay intersection-free and gain no energy, auto
// substeps converge, friction holds on a slope, and any thread count gives the same bits.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/collision/contact_accuracy.hpp"
#include "core/dynamics/energy.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/mesh/mesh_topology.hpp"
#include "core/scene/material.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "importers/bench_scenes.hpp"
#include "importers/scene_file.hpp"
#include "tests/core/test_worlds.hpp"
#include "tests/support/intersection_checker.hpp"

namespace softbake {
namespace {

/// The two-layer pile of eight rubber balls (balls10k) or figure 7, `frames` frames.
SceneSetup pileOrFigure7(const std::string& name, int frames) {
  SceneSetup scene = name == "balls10k" ? benchScene("balls10k")->setup
                                        : loadSceneFile(std::filesystem::path(SOFTBAKE_SOURCE_DIR) /
                                                        "examples" / "fig7_10k_faces.json")
                                              .setup;
  scene.settings.frames = frames;
  scene.settings.collisions.contactsInStep = true;
  return scene;
}

struct SteppedRun {
  std::size_t worstBetween = 0;  ///< most intersecting pairs between bodies on a frame
  double energyRise = 0;         ///< most the total energy rose above its start at a frame's end
  double meanSubsteps = 0;
  std::vector<Vec3d> centroids;  ///< per body, at the end
  std::vector<double> volumes;   ///< per closed body, at the end
};

SteppedRun simulate(SceneSetup scene, int substeps) {
  scene.settings.substeps = substeps;
  scene.settings.collisions.contactsInStep = true;
  Simulator simulator(buildSceneTopology(scene));
  const double start = computeEnergy(simulator.topology(), simulator.state()).total();
  SteppedRun run;
  for (int frame = 2; frame <= scene.settings.frames; ++frame) {
    simulator.advanceToFrame(frame);
    run.meanSubsteps += simulator.substeps().substeps;
    run.worstBetween =
        std::max(run.worstBetween,
                 test::countIntersectingPairs(simulator.collision(), simulator.state().position)
                     .betweenSurfaces);
    run.energyRise = std::max(
        run.energyRise, computeEnergy(simulator.topology(), simulator.state()).total() - start);
  }
  run.meanSubsteps /= scene.settings.frames - 1;
  const SceneTopology& topology = simulator.topology();
  for (const Body& body : topology.bodies) {
    Vec3d sum = Vec3d::Zero();
    for (Index i = body.firstParticle; i < body.firstParticle + body.particleCount; ++i)
      sum += simulator.state().position[i].cast<double>();
    run.centroids.push_back(sum / double(body.particleCount));
    run.volumes.push_back(signedVolume(std::span<const Vec3f>(simulator.state().position),
                                       topology.bodyTriangles(body)));
  }
  return run;
}

class LargeSteps : public ::testing::TestWithParam<std::string> {};

/// At 1, 2 and 4 substeps a frame, far fewer than the collision stages alone need: 0 pairs between
/// bodies on every frame by the exact checker; from 2 substeps on, no energy gained either (the
/// response alone gained 15 kJ on the pile at 2 substeps).
TEST_P(LargeSteps, StayIntersectionFreeAndFromTwoSubstepsGainNoEnergy) {
  for (int substeps : {1, 2, 4}) {
    const SteppedRun run = simulate(pileOrFigure7(GetParam(), 24), substeps);
    EXPECT_EQ(run.worstBetween, 0u) << substeps << " substeps a frame";
    if (substeps >= 2) {
      EXPECT_LT(run.energyRise, 1.0) << substeps << " substeps a frame";
    }
  }
}

/// The resting state at "auto" agrees with 4× its substeps: each body's height (its centroid's)
/// within 2% of its size, its volume within 2%, on a scene that comes to rest in one way (a heavy
/// ball on jelly): where the balls of a pile scatter to is chaotic, and agrees at no step size.
class RestingState : public ::testing::TestWithParam<std::string> {};

TEST_P(RestingState, AtAutoSubstepsAgreesWithFourTimesAsMany) {
  SceneSetup scene = loadSceneFile(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "examples" /
                                   (GetParam() + ".json"))
                         .setup;
  scene.settings.frames = 96;
  const SteppedRun automatic = simulate(scene, 0);
  EXPECT_LE(automatic.meanSubsteps, 6.0);
  const SteppedRun fine = simulate(scene, int(std::ceil(4 * automatic.meanSubsteps)));
  const SceneTopology topology = buildSceneTopology(scene);
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    Box3 bounds;
    for (Index i = topology.bodies[b].firstParticle;
         i < topology.bodies[b].firstParticle + topology.bodies[b].particleCount; ++i)
      bounds.extend(topology.restPosition[i]);
    const double size = double(bounds.sizes().maxCoeff());
    EXPECT_LT(std::abs(automatic.centroids[b].y() - fine.centroids[b].y()), 0.02 * size)
        << topology.bodies[b].name;
    EXPECT_LT(std::abs(automatic.volumes[b] / fine.volumes[b] - 1), 0.02)
        << topology.bodies[b].name;
  }
}

INSTANTIATE_TEST_SUITE_P(Settling, RestingState, ::testing::Values("heavy_on_jelly"));

INSTANTIATE_TEST_SUITE_P(PileAndFigure7, LargeSteps, ::testing::Values("balls10k", "fig7"));

/// "auto" with the contacts in the step: surfaces may close by a whole short edge per substep, ten
/// times what the contacts after the step allow, from the same closing speed. Two rubber balls
/// 0.4 m apart, each at `speed` toward the other; the rule's closing speed is the faster body's
/// fastest vertex, `speed`.
TEST(ContactsInStep, AutoSubstepsLetSurfacesCloseByAWholeShortEdge) {
  const auto twoBalls = [](float speed, bool inStep) {
    SceneSetup scene =
        test::twoBallsOnX(*findMaterialPreset("rubber"), Vec3(speed, 0, 0), Vec3(-speed, 0, 0));
    scene.settings.collisions.contactsInStep = inStep;
    return buildSceneTopology(scene);
  };
  for (float speed : {6.0f, 30.0f}) {
    const SceneTopology topology = twoBalls(speed, true);
    const SubstepChoice after = Simulator(twoBalls(speed, false)).substeps();
    const SubstepChoice inStep = Simulator(topology).substeps();
    EXPECT_TRUE(inStep.automatic);
    EXPECT_NEAR(inStep.closingSpeed, after.closingSpeed, 1e-6) << speed << " m/s";
    EXPECT_NEAR(inStep.closingSpeed, speed, 1e-3) << speed << " m/s";
    // The closing within a frame over a whole reach (skin and short edge), against a tenth of it.
    const double reach = double(topology.settings.skin) + contactEdgeLength(topology);
    const double frame = 1 / topology.settings.fps;
    const auto expected = [&](double fraction) {
      return std::clamp(int(std::ceil(speed * frame / (fraction * reach))), kMinAutoSubsteps,
                        kMaxAutoSubsteps);
    };
    EXPECT_EQ(inStep.substeps, expected(1.0)) << speed << " m/s";
    EXPECT_EQ(after.substeps, expected(0.1)) << speed << " m/s";
    EXPECT_GT(inStep.substeps, kMinAutoSubsteps) << speed << " m/s";
    EXPECT_LT(inStep.substeps, after.substeps) << speed << " m/s";
  }
}

/// A ball resting on a ball, one step a frame, for 10 s: the energy never rises above its start.
/// (Balanced on top, it may roll off; held on the lower ball for its first frames either way.)
TEST(ContactsInStep, ABallRestingOnABallAtOneStepAFrameGainsNoEnergy) {
  SceneSetup scene;
  scene.settings.frames = 241;
  scene.settings.substeps = 1;
  scene.settings.collisions.contactsInStep = true;
  BodySetup lower;
  lower.name = "lower";
  lower.mesh = makeIcosphere(3, 0.4f, Vec3f(0, 0.401f, 0));
  lower.material = *findMaterialPreset("rubber");
  BodySetup upper = lower;
  upper.name = "upper";
  upper.mesh = makeIcosphere(3, 0.4f, Vec3f(0, 1.203f, 0));
  scene.bodies = {lower, upper};
  scene.planes.push_back(PlaneCollider{});
  Simulator simulator(buildSceneTopology(scene));
  const double start = computeEnergy(simulator.topology(), simulator.state()).total();
  double rise = 0;
  int heldFrames = 0;
  for (int frame = 2; frame <= scene.settings.frames; ++frame) {
    simulator.advanceToFrame(frame);
    heldFrames += simulator.lastFrameStats().heldContacts > 0;
    rise = std::max(rise, computeEnergy(simulator.topology(), simulator.state()).total() - start);
    ASSERT_EQ(test::countIntersectingPairs(simulator.collision(), simulator.state().position)
                  .betweenSurfaces,
              0u)
        << "frame " << frame;
  }
  EXPECT_LT(rise, 0.01) << "J above the start";
  EXPECT_GT(heldFrames, 40) << "frames on which the solve held the upper ball on the lower one";
}

/// Two parallel square sheets of one open body, 0.7 mm apart: closer than the 1 mm skin the
/// contacts keep, as the walls and fillets of a CAD part often are. Nothing loads them (no
/// gravity), so nothing may move them: the solve leaves a vertex the scene placed within the gap of
/// a triangle where it is, as the failsafe does. Held to the gap, the sheets were pushed apart and
/// buckled, a particle by 7.2 mm (and an engine's parts, each pushed into the next, took four times
/// as long a step).
TEST(ContactsInStep, SurfacesTheScenePlacedWithinTheGapStayWhereTheyAre) {
  constexpr int kSide = 8;
  constexpr float kSize = 0.1f, kApart = 0.0007f;
  TriangleMesh sheets;
  sheets.name = "sheets";
  for (float y : {0.5f, 0.5f + kApart}) {
    const Index first = Index(sheets.positions.size());
    for (int i = 0; i <= kSide; ++i)
      for (int k = 0; k <= kSide; ++k)
        sheets.positions.emplace_back(kSize * float(i) / kSide, y, kSize * float(k) / kSide);
    for (int i = 0; i < kSide; ++i)
      for (int k = 0; k < kSide; ++k) {
        const Index a = first + Index(i * (kSide + 1) + k), b = a + 1, c = a + kSide + 1;
        sheets.triangles.push_back({a, b, c + 1});
        sheets.triangles.push_back({a, c + 1, c});
      }
  }
  SceneSetup scene;
  scene.settings.frames = 25;
  scene.settings.substeps = 2;
  scene.settings.gravity = Vec3::Zero();
  scene.settings.collisions.contactsInStep = true;
  BodySetup body;
  body.name = "sheets";
  body.mesh = sheets;
  body.material = *findMaterialPreset("rubber");
  scene.bodies = {body};
  Simulator simulator(buildSceneTopology(scene));
  ASSERT_GT(simulator.topology().settings.skin, kApart) << "the sheets start within the skin";
  const std::vector<Vec3> start = simulator.state().position;
  for (int frame = 2; frame <= scene.settings.frames; ++frame) simulator.advanceToFrame(frame);
  double moved = 0;
  for (std::size_t i = 0; i < start.size(); ++i)
    moved = std::max(moved, double((simulator.state().position[i] - start[i]).norm()));
  EXPECT_LT(moved, 1e-5) << "m, the most any particle moved";
}

/// Two walls of a house butting edge to edge in one plane, 1.5 skins apart, each a square metre of
/// two triangles (so the feet of one's corners lie within 2% of the other's triangles),
/// and a third, finely and unevenly cut part of a few grams beside them: falling freely, no
/// stencil holds anything and every part keeps its shape. Before: the walls' corners were held a
/// skin out of their plane (10 stencils held, a wall 2.1 mm out of it); a house of 294 parts took
/// 20 s a step in its failsafe. (The first solve's start from free fall, which kept a house's light
/// fittings in shape, is ImplicitEuler.AFreeFallFromRestIsSolvedWithoutAnIteration: this fan keeps
/// its shape without it too.)
TEST(ContactsInStep, PartsFallingTogetherHoldNothingAndKeepTheirShapes) {
  constexpr float kApart = 0.0015f;
  std::vector<TriangleMesh> parts(2);
  for (int w = 0; w < 2; ++w) {
    const float x0 = float(w) * (1.0f + kApart);
    parts[w].name = cat("wall", w);
    for (float y : {0.0f, 1.0f})
      for (float z : {0.0f, 1.0f}) parts[w].positions.emplace_back(x0 + y, 1.0f, z);
    parts[w].triangles = {{0, 1, 3}, {0, 3, 2}};
  }
  // A fan whose slivers give its particles masses a hundred times apart.
  TriangleMesh& fitting = parts.emplace_back();
  fitting.name = "fitting";
  constexpr int kSlices = 60;
  fitting.positions.emplace_back(0.5f, 1.3f, 0.5f);
  for (int k = 0; k <= kSlices; ++k) {
    const float angle = 1.5f * float(k * k) / (kSlices * kSlices);
    fitting.positions.emplace_back(0.5f + 0.05f * std::cos(angle), 1.3f,
                                   0.5f + 0.05f * std::sin(angle));
    if (k > 0) fitting.triangles.push_back({0, Index(k), Index(k + 1)});
  }
  SceneSetup scene;
  scene.settings.frames = 2;
  scene.settings.substeps = 4;
  scene.settings.collisions.contactsInStep = true;
  for (const TriangleMesh& mesh : parts) {
    BodySetup body;
    body.name = mesh.name;
    body.mesh = mesh;
    body.material = *findMaterialPreset("rubber");
    body.mass = mesh.name == "fitting" ? 0.005f : 1;
    scene.bodies.push_back(body);
  }
  Simulator simulator(buildSceneTopology(scene));
  const double skin = simulator.topology().settings.skin;
  // Not fitted (within the skin), but each in the other's boxes (grown by the skin each).
  ASSERT_LT(skin, kApart) << "the walls butt further apart than the skin";
  ASSERT_GT(2 * skin, kApart) << "the walls are candidates of each other";
  const std::vector<Vec3> start = simulator.state().position;
  simulator.advanceToFrame(2);
  EXPECT_EQ(simulator.lastFrameStats().heldContacts, 0u);
  // Free fall moves every particle alike; the distance any particle departs from that is how far
  // its part lost its shape.
  for (const Body& body : simulator.topology().bodies) {
    Vec3d mean = Vec3d::Zero();
    const Index end = body.firstParticle + body.particleCount;
    for (Index i = body.firstParticle; i < end; ++i)
      mean += (simulator.state().position[i] - start[i]).cast<double>();
    mean /= double(body.particleCount);
    double departed = 0;
    for (Index i = body.firstParticle; i < end; ++i)
      departed = std::max(
          departed, ((simulator.state().position[i] - start[i]).cast<double>() - mean).norm());
    EXPECT_LT(departed, 1e-3 * skin) << body.name << ": m, the most a particle departed";
  }
}

/// A box-like rubber body on a 20° static slope (a mesh, not a plane): with friction 0.6 (more than
/// tan 20° = 0.36) it stays put, with 0.1 it slides. Measured: 1.3 mm and 1.6 m; with friction
/// applied after the solve instead, the block slid 0.5 m even at friction 4.
double slideOnSlope(float friction) {
  SceneSetup scene;
  scene.settings.frames = 49;
  scene.settings.collisions.contactsInStep = true;
  BodySetup block;
  block.name = "block";
  // A coarse icosphere flattened into a slab reads as a box to the slope: a broad, flat base.
  block.mesh = makeIcosphere(2, 0.3f, Vec3f(0, 0, 0));
  for (Vec3f& p : block.mesh.positions) p.y() *= 0.4f;
  block.material = *findMaterialPreset("stiff");
  scene.settings.collisions.friction = friction;  // the bodies' side of every contact
  const float angle = 20.0f * float(M_PI) / 180.0f;
  const Eigen::Matrix3f tilt =
      Eigen::AngleAxisf(angle, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  // Resting on the slope from the start, a skin and a bit above it.
  for (Vec3f& p : block.mesh.positions) p = tilt * (p + Vec3f(0, 0.121f + 0.002f, 0));
  StaticMeshCollider slope;
  slope.name = "slope";
  slope.friction = friction;
  const int n = 8;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      slope.mesh.positions.push_back(tilt * Vec3f(-2 + 4.0f * i / n, 0, -2 + 4.0f * j / n));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Index a = Index(j * (n + 1) + i), b = a + 1, c = a + Index(n + 1), d = c + 1;
      slope.mesh.triangles.push_back({a, c, b});
      slope.mesh.triangles.push_back({b, c, d});
    }
  scene.bodies = {block};
  scene.staticMeshes = {slope};
  Simulator simulator(buildSceneTopology(scene));
  const Vec3f down = tilt * Vec3f(-1, 0, 0);  // down the slope
  const auto along = [&] {
    double sum = 0;
    for (const Vec3& p : simulator.state().position) sum += double(down.dot(p));
    return sum / double(simulator.state().position.size());
  };
  // From half a second on, once it has settled onto the slope.
  double start = 0;
  for (int frame = 2; frame <= scene.settings.frames; ++frame) {
    simulator.advanceToFrame(frame);
    if (frame == 13) start = along();
  }
  return along() - start;
}

TEST(ContactsInStep, FrictionHoldsABodyOnASlopeOrLetsItSlide) {
  const double held = slideOnSlope(0.6f), slid = slideOnSlope(0.1f);
  EXPECT_LT(std::abs(held), 0.01) << "m down the slope from 0.5 s to 2 s at friction 0.6";
  EXPECT_GT(slid, 0.3) << "m down the slope from 0.5 s to 2 s at friction 0.1";
}

/// The pile with its contacts in the step, bit for bit on 1, 2, 3 and 4 threads.
std::vector<Vec3> pileOnThreads(int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  tbb::task_arena arena(threads);
  return arena.execute([&] {
    SceneSetup scene = pileOrFigure7("balls10k", 12);
    scene.settings.substeps = 2;
    Simulator simulator(buildSceneTopology(scene));
    for (int frame = 2; frame <= scene.settings.frames; ++frame) simulator.advanceToFrame(frame);
    return simulator.state().position;
  });
}

TEST(ContactsInStep, AnyThreadCountGivesBitIdenticalPositions) {
  const std::vector<Vec3> one = pileOnThreads(1);
  for (int threads : {2, 3, 4}) {
    const std::vector<Vec3> many = pileOnThreads(threads);
    ASSERT_EQ(one.size(), many.size());
    for (std::size_t i = 0; i < one.size(); ++i)
      ASSERT_EQ(one[i], many[i]) << "particle " << i << " at " << threads << " threads";
  }
}

}  // namespace
}  // namespace softbake
