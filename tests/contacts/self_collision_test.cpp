// Self-collision on by default (BodySetup::selfCollision unset), for open and closed bodies alike,
// and the normal-cone culling that makes it affordable (core/collision/self_patches.hpp), checked
// against an exact triangle-pair test over every pair.
// That every example then keeps 0 intersecting pairs within each body on every frame is checked by
// ExampleContacts (example_contacts_test.cpp), which counts a self-colliding body's own pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/broad_phase/pair_cache.hpp"
#include "core/collision/geometry.hpp"
#include "core/collision/self_patches.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/scene/material.hpp"
#include "core/simulator.hpp"
#include "importers/scene_file.hpp"
#include "tests/core/test_worlds.hpp"
#include "tests/support/definition_pairs.hpp"
#include "tests/support/intersection_checker.hpp"

namespace softbake {
namespace {

using test::definitionPairs;

/// An example with every body's self_collision key removed: the default.
SceneSetup exampleByDefault(const std::string& name) {
  SceneSetup scene =
      loadSceneFile(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "examples" / (name + ".json"))
          .setup;
  for (BodySetup& body : scene.bodies) body.selfCollision.reset();
  return scene;
}

/// A sheet of n × n quads in the xz plane, 1 m wide, as the one self-colliding soft surface of a
/// collision geometry, optionally followed by a ball that does not self-collide.
struct Sheet {
  int n = 24;
  std::vector<Vec3> rest;
  CollisionGeometry geometry;

  explicit Sheet(int quads, bool withBall = false) : n(quads) {
    for (int z = 0; z <= n; ++z)
      for (int x = 0; x <= n; ++x)
        rest.push_back(Vec3(Scalar(x) / n - 0.5f, 0, Scalar(z) / n - 0.5f));
    std::vector<Triangle>& t = geometry.triangleVertices;
    for (int z = 0; z < n; ++z)
      for (int x = 0; x < n; ++x) {
        const Index a = Index(z * (n + 1) + x), c = a + Index(n) + 1;
        t.push_back({a, c, a + 1});
        t.push_back({a + 1, c, c + 1});
      }
    geometry.surfaces.push_back({0, Index(t.size()), true, true});
    if (withBall) {
      const TriangleMesh ball = makeIcosphere(2, 0.3f, Vec3f(0, 1, 0));
      const Index base = Index(rest.size()), first = Index(t.size());
      for (const Vec3f& p : ball.positions) rest.push_back(p.cast<Scalar>());
      for (const Triangle& k : ball.triangles) t.push_back({base + k[0], base + k[1], base + k[2]});
      geometry.surfaces.push_back({first, Index(ball.triangles.size()), true, false});
    }
    for (std::size_t s = 0; s < geometry.surfaces.size(); ++s)
      geometry.triangleSurface.insert(geometry.triangleSurface.end(),
                                      geometry.surfaces[s].triangleCount, Index(s));
    geometry.particleCount = Index(rest.size());
    geometry.softTriangleCount = Index(t.size());
    geometry.selfPatches = buildSelfPatches(geometry, rest);
  }

  /// The sheet crumpled by a smooth random field of amplitude `amplitude` (m) on every axis:
  /// from about 0.3 m on, it passes through itself.
  std::vector<Vec3> crumpled(std::mt19937& rng, Scalar amplitude) const {
    std::uniform_real_distribution<Scalar> unit(-1, 1);
    struct Wave {
      Vec3 direction;
      Scalar k, phase;
      Vec3 amplitude;
    };
    std::vector<Wave> waves;
    for (int w = 0; w < 6; ++w)
      waves.push_back({Vec3(unit(rng), 0, unit(rng)).normalized(), 4 + 4 * std::abs(unit(rng)),
                       3 * unit(rng), amplitude * Vec3(unit(rng), unit(rng), unit(rng)) / 2});
    std::vector<Vec3> out = rest;
    for (std::size_t v = 0; v < out.size() && v < std::size_t((n + 1) * (n + 1)); ++v)
      for (const Wave& w : waves)
        out[v] += w.amplitude * std::sin(w.k * w.direction.dot(rest[v]) + w.phase);
    return out;
  }

  /// Each triangle's box over its motion from `start` to `end`, grown by `margin`.
  std::vector<Box3> boxes(const std::vector<Vec3>& start, const std::vector<Vec3>& end,
                          Scalar margin = 0.002f) const {
    std::vector<Box3> out;
    for (const Triangle& t : geometry.triangleVertices) {
      Box3 box;
      for (Index v : t) box.extend(start[v]).extend(end[v]);
      out.push_back(Box3(box.min().array() - margin, box.max().array() + margin));
    }
    return out;
  }
};

/// An icosphere of 1 280 faces at the origin, the one self-colliding surface of a geometry.
struct Ball {
  std::vector<Vec3> positions;
  CollisionGeometry geometry;

  explicit Ball(float radius) {
    const TriangleMesh mesh = makeIcosphere(3, radius, Vec3f::Zero());
    for (const Vec3f& p : mesh.positions) positions.push_back(p.cast<Scalar>());
    geometry.triangleVertices = mesh.triangles;
    geometry.triangleSurface.assign(mesh.triangles.size(), 0);
    geometry.surfaces.push_back({0, Index(mesh.triangles.size()), true, true});
    geometry.particleCount = Index(positions.size());
    geometry.softTriangleCount = Index(mesh.triangles.size());
    geometry.selfPatches = buildSelfPatches(geometry, positions);
  }
};

/// Every pair of the sheet's own triangles that share no vertex and cross, by the exact test.
std::vector<TrianglePair> crossingPairs(const CollisionGeometry& geometry,
                                        const std::vector<Vec3>& positions) {
  std::vector<TrianglePair> pairs;
  TrianglePairHits hits;
  const CollisionSurface& sheet = geometry.surfaces[0];
  for (Index i = sheet.firstTriangle; i < sheet.firstTriangle + sheet.triangleCount; ++i)
    for (Index j = i + 1; j < sheet.firstTriangle + sheet.triangleCount; ++j) {
      if (geometry.trianglesCross(positions, i, j, hits)) pairs.push_back({i, j});
    }
  return pairs;
}

std::vector<TrianglePair> candidates(BroadPhaseKind kind, const BroadPhaseInput& input) {
  std::vector<TrianglePair> pairs;
  makeBroadPhase(kind)->findPairs(input, pairs);
  return pairs;
}

std::size_t count(const std::vector<std::uint8_t>& flags) {
  return std::size_t(std::count(flags.begin(), flags.end(), std::uint8_t(1)));
}

TEST(SelfCollision, IsOnByDefaultForOpenAndClosedBodies) {
  for (const char* name : {"flag_fold", "mixed_pile"}) {
    const SceneTopology topology = buildSceneTopology(exampleByDefault(name));
    for (const Body& body : topology.bodies) EXPECT_TRUE(body.selfCollision) << body.name;
  }
}

/// The most intersecting pairs within the lower ball on any frame: a jelly ball of the paper's gas
/// law (no bulk term to keep it round) on the ground, and a stiff ball ten times as heavy thrown
/// onto it at 4 m/s, which presses it into the ground, under the scene's defaults but for the
/// jelly ball's `selfCollision`.
std::size_t mostPairsWithinABallPressedIntoTheGround(std::optional<bool> selfCollision) {
  Material jelly = *findMaterialPreset("jelly");
  jelly.bulkModulus = 0;  // as the figure examples keep it
  SceneSetup scene = test::ballScene(jelly, 3, 0.3f, Vec3f(0, 0.31f, 0));
  scene.settings.frames = 36;
  scene.bodies[0].selfCollision = selfCollision;
  BodySetup weight;
  weight.name = "weight";
  weight.mesh = makeIcosphere(3, 0.25f, Vec3f(0.03f, 0.9f, 0));
  weight.material = *findMaterialPreset("stiff");
  weight.mass = 10;
  weight.velocity = Vec3(0, -4, 0);
  scene.bodies.push_back(weight);
  Simulator simulator(buildSceneTopology(scene));
  std::size_t most = 0;
  for (int frame = 2; frame <= scene.settings.frames; ++frame) {
    simulator.advanceToFrame(frame);
    const test::IntersectionCount count =
        test::countIntersectingPairs(simulator.collision(), simulator.state().position);
    const auto within = count.bySurfaces.find({0, 0});
    most = std::max(most, within == count.bySurfaces.end() ? std::size_t(0) : within->second);
  }
  return most;
}

TEST(SelfCollision, ABallPressedHardIntoTheGroundNeverCrossesItself) {
  EXPECT_EQ(mostPairsWithinABallPressedIntoTheGround(std::nullopt), 0u) << "the default";
  EXPECT_GT(mostPairsWithinABallPressedIntoTheGround(false), 0u)
      << "without self-collision the ball creases into itself: the load is hard enough to tell";
}

TEST(SelfPatches, CoverTheSelfCollidingTrianglesOnceInConnectedPatchesOfAtMost32) {
  const Sheet sheet(24, /*withBall=*/true);
  const SelfPatches& patches = sheet.geometry.selfPatches;
  const CollisionSurface& own = sheet.geometry.surfaces[0];
  ASSERT_GT(patches.patchCount(), 4u);
  std::vector<int> seen(sheet.geometry.triangleVertices.size(), 0);
  for (std::size_t p = 0; p < patches.patchCount(); ++p) {
    const auto members =
        std::span(patches.triangles)
            .subspan(patches.patchStart[p], patches.patchStart[p + 1] - patches.patchStart[p]);
    ASSERT_GE(members.size(), 1u);
    EXPECT_LE(members.size(), 32u);
    for (Index t : members) {
      ++seen[t];
      EXPECT_EQ(patches.trianglePatch[t], p);
    }
    // Connected over shared edges: a flood from the first member reaches them all.
    std::vector<Index> reached{members[0]};
    for (std::size_t head = 0; head < reached.size(); ++head)
      for (Index t : members) {
        if (std::find(reached.begin(), reached.end(), t) != reached.end()) continue;
        int shared = 0;
        for (Index v : sheet.geometry.triangleVertices[t])
          shared += hasVertex(sheet.geometry.triangleVertices[reached[head]], v);
        if (shared == 2) reached.push_back(t);
      }
    EXPECT_EQ(reached.size(), members.size()) << "patch " << p;
  }
  for (Index t = 0; t < seen.size(); ++t) {
    if (t < own.triangleCount) {
      EXPECT_EQ(seen[t], 1) << "sheet triangle " << t;
    } else {
      EXPECT_EQ(seen[t], 0) << "ball triangle " << t;  // the ball does not self-collide
      EXPECT_EQ(patches.trianglePatch[t], kNoPatch);
    }
  }
}

TEST(SelfPatches, ARoundBallIsFlatEverywhereAndAFoldedSheetIsNotAcrossOrWhereItTurns) {
  const Ball ball(1.0f);
  PatchFlatness flatness;
  updateFlatPatches(ball.geometry, ball.positions, ball.positions, flatness);
  ASSERT_GE(flatness.flat.size(), 10u);
  EXPECT_EQ(count(flatness.flat), flatness.flat.size());

  // Folded shut along x = 0: the half x > 0 turned over onto the other, 1 cm above it. The patches
  // across the fold face both ways; those on either side are flat.
  const Sheet sheet(24);
  std::vector<Vec3> folded = sheet.rest;
  for (Vec3& p : folded)
    if (p.x() > 0) p = Vec3(-p.x(), Scalar(0.01), p.z());
  updateFlatPatches(sheet.geometry, sheet.rest, sheet.rest, flatness);
  EXPECT_EQ(count(flatness.flat), flatness.flat.size());
  EXPECT_EQ(count(flatness.flatWith), flatness.flatWith.size())
      << "a flat sheet is one height field";
  PatchFlatness turning;  // flat at the start, folded at the end
  updateFlatPatches(sheet.geometry, folded, folded, flatness);
  updateFlatPatches(sheet.geometry, sheet.rest, folded, turning);
  const std::vector<std::uint8_t>& flat = flatness.flat;
  const SelfPatches& patches = sheet.geometry.selfPatches;
  // Per patch: 1 with a triangle left of the fold, 2 with one turned over, 3 both.
  std::vector<int> side(flat.size(), 0);
  for (std::size_t p = 0; p < flat.size(); ++p)
    for (Index k = patches.patchStart[p]; k < patches.patchStart[p + 1]; ++k) {
      // A triangle with a corner at x > 0 is turned over; the others stay.
      bool turned = false;
      for (Index v : sheet.geometry.triangleVertices[patches.triangles[k]])
        turned = turned || sheet.rest[v].x() > 0;
      side[p] |= turned ? 2 : 1;
    }
  std::size_t straddling = 0, besideAsOne = 0;
  for (std::size_t p = 0; p < flat.size(); ++p) {
    straddling += side[p] == 3;
    EXPECT_EQ(bool(flat[p]), side[p] != 3) << "patch " << p;
    // Over the substep, a patch that turns over passes through everything: not flat either.
    EXPECT_EQ(bool(turning.flat[p]), side[p] == 1) << "patch " << p;
    for (Index k = patches.neighbourStart[p]; k < patches.neighbourStart[p + 1]; ++k) {
      const Index q = patches.neighbours[k];
      if (side[p] == 3 || side[q] == 3) continue;
      // Neighbours on one side of the fold lie in one plane: always flat as one. (None lie
      // wholly on opposite sides: a patch that straddles the fold parts them.)
      besideAsOne += side[p] == side[q] && flatness.flatWith[k];
      EXPECT_EQ(bool(flatness.flatWith[k]), side[p] == side[q]) << "patches " << p << ", " << q;
    }
  }
  EXPECT_GT(straddling, 0u);
  EXPECT_GT(besideAsOne, 0u);
}

TEST(SelfPatches, NeighboursAreThePatchesThatShareAVertexAndAgreeWhetherTheyAreFlatAsOne) {
  const Sheet sheet(24, /*withBall=*/true);
  const SelfPatches& patches = sheet.geometry.selfPatches;
  ASSERT_EQ(patches.neighbourStart.size(), patches.patchCount() + 1);
  std::mt19937 rng(11);
  PatchFlatness flatness;
  updateFlatPatches(sheet.geometry, sheet.rest, sheet.crumpled(rng, Scalar(0.3)), flatness);
  std::size_t pairs = 0;
  for (Index p = 0; p < patches.patchCount(); ++p)
    for (Index q = 0; q < patches.patchCount(); ++q) {
      bool share = false;  // brute force over the two patches' corners
      for (Index a = patches.patchStart[p]; a < patches.patchStart[p + 1] && !share; ++a)
        for (Index b = patches.patchStart[q]; b < patches.patchStart[q + 1] && !share; ++b)
          for (Index v : sheet.geometry.triangleVertices[patches.triangles[b]])
            share = share || hasVertex(sheet.geometry.triangleVertices[patches.triangles[a]], v);
      const auto begin = patches.neighbours.begin() + patches.neighbourStart[p];
      const auto end = patches.neighbours.begin() + patches.neighbourStart[p + 1];
      const auto at = std::lower_bound(begin, end, q);
      const bool listed = at != end && *at == q;
      EXPECT_EQ(listed, p != q && share) << "patches " << p << ", " << q;
      if (!listed) continue;
      ++pairs;
      // The other's entry for this one says the same.
      const auto back =
          std::lower_bound(patches.neighbours.begin() + patches.neighbourStart[q],
                           patches.neighbours.begin() + patches.neighbourStart[q + 1], p);
      EXPECT_EQ(flatness.flatWith[std::size_t(at - patches.neighbours.begin())],
                flatness.flatWith[std::size_t(back - patches.neighbours.begin())]);
    }
  EXPECT_GT(pairs, patches.patchCount());
  EXPECT_TRUE(std::is_sorted(patches.neighbours.begin() + patches.neighbourStart[0],
                             patches.neighbours.begin() + patches.neighbourStart[1]));
}

/// The foot of a CAD part's cylinder, as the two-cylinder engine models it: a cap facing down (a
/// fan of 4 triangles around its centre, 40 mm across) and the wall above its rim (8 triangles,
/// 20 mm high, facing out), welded at one vertex only. Every other foot vertex of the wall stands
/// 2 µm outside the cap's rim: an unwelded seam. The cap and the wall are two patches, neighbours
/// at the welded vertex, whose cones merge within 60°.
struct CapAndWall {
  std::vector<Vec3> rest;
  CollisionGeometry geometry;
  static constexpr Scalar kRadius = 0.04f, kHeight = 0.02f, kSeam = 2e-6f;

  CapAndWall() {
    const auto around = [](Scalar radius, int k, Scalar y) {
      const Scalar angle = Scalar(k) * Scalar(std::numbers::pi / 12);  // 15° apart
      return Vec3(radius * std::cos(angle), y, radius * std::sin(angle));
    };
    rest.push_back(Vec3::Zero());                                        // 0: the cap's centre
    for (int k = 0; k <= 4; ++k) rest.push_back(around(kRadius, k, 0));  // 1–5: its rim
    std::vector<Triangle>& t = geometry.triangleVertices;
    for (Index k = 1; k <= 4; ++k) t.push_back({0, k, k + 1});  // normals −y
    // The wall's foot (6–9, after the welded 1) and top (10–14).
    for (int k = 1; k <= 4; ++k) rest.push_back(around(kRadius + kSeam, k, 0));
    for (int k = 0; k <= 4; ++k) rest.push_back(around(kRadius, k, kHeight));
    const auto foot = [](Index k) { return k == 0 ? Index(1) : Index(5 + k); };
    for (Index k = 0; k < 4; ++k) {  // normals outward
      t.push_back({foot(k), 10 + k, foot(k + 1)});
      t.push_back({foot(k + 1), 10 + k, 11 + k});
    }
    geometry.surfaces.push_back({0, Index(t.size()), true, true});
    geometry.triangleSurface.assign(t.size(), 0);
    geometry.particleCount = Index(rest.size());
    geometry.softTriangleCount = Index(t.size());
    geometry.selfPatches = buildSelfPatches(geometry, rest);
  }
};

TEST(SelfPatches, ACapAndAWallWhoseUnweldedSeamTouchesAreNeverFlatAsOne) {
  const CapAndWall part;
  const SelfPatches& patches = part.geometry.selfPatches;
  ASSERT_EQ(patches.patchCount(), 2u);
  ASSERT_EQ(patches.neighbourStart[1] - patches.neighbourStart[0], 1u);
  // One foot vertex of the wall, 50 µm in and 10 µm down: its wall triangles go through the cap,
  // while every normal stays where it was within a few degrees.
  std::vector<Vec3> end = part.rest;
  end[7] = Vec3(end[7].x(), -1e-5f, end[7].z()) * (1 - 5e-5f / CapAndWall::kRadius);
  const test::IntersectionCount crossing = test::countIntersectingPairs(part.geometry, end);
  ASSERT_GT(crossing.withinSurfaces, 0u);
  PatchFlatness flatness;
  updateFlatPatches(part.geometry, part.rest, end, flatness);
  // Each alone is a height field; as one they are not, though their cones would pass.
  EXPECT_TRUE(flatness.flat[0] && flatness.flat[1]);
  EXPECT_EQ(flatness.flatWith[0], 0);
  EXPECT_EQ(flatness.flatWith[1], 0);
  std::vector<Box3> boxes;
  for (const Triangle& t : part.geometry.triangleVertices) {
    Box3 box;
    for (Index v : t) box.extend(part.rest[v]).extend(end[v]);
    boxes.push_back(Box3(box.min().array() - 0.001f, box.max().array() + 0.001f));
  }
  const BroadPhaseInput input = part.geometry.broadPhaseInput(boxes, &flatness);
  const std::vector<TrianglePair> eligible = definitionPairs(input);
  for (const auto& [a, b] : crossing.pairs)
    EXPECT_TRUE(std::binary_search(eligible.begin(), eligible.end(), TrianglePair{a, b}))
        << "triangles " << a << " and " << b << " cross, and no broad phase would list them";
}

TEST(SelfPatches, ARampWoundPastOneTurnIsNeverFlat) {
  // A spiral ramp of 30 triangles, 1¼ turns 1 mm apart: its normals tilt by 0.6° at most, a
  // height field by its cone, but seen from above it lies over itself.
  std::vector<Vec3> rest;
  CollisionGeometry geometry;
  for (int k = 0; k <= 15; ++k) {
    const double angle = 2.5 * std::numbers::pi * k / 15, y = 1e-3 * angle / (2 * std::numbers::pi);
    for (double radius : {0.05, 0.1})
      rest.push_back(
          Vec3(Scalar(radius * std::cos(angle)), Scalar(y), Scalar(-radius * std::sin(angle))));
  }
  std::vector<Triangle>& t = geometry.triangleVertices;
  for (Index k = 0; k < 15; ++k) {
    t.push_back({2 * k, 2 * k + 1, 2 * k + 2});
    t.push_back({2 * k + 2, 2 * k + 1, 2 * k + 3});
  }
  geometry.surfaces.push_back({0, Index(t.size()), true, true});
  geometry.triangleSurface.assign(t.size(), 0);
  geometry.particleCount = Index(rest.size());
  geometry.softTriangleCount = Index(t.size());
  geometry.selfPatches = buildSelfPatches(geometry, rest);
  ASSERT_EQ(geometry.selfPatches.patchCount(), 1u);
  PatchFlatness flatness;
  updateFlatPatches(geometry, rest, rest, flatness);
  EXPECT_LT(flatness.halfAngle[0], 0.02);  // the cone alone would cull its pairs
  EXPECT_EQ(flatness.flat[0], 0);
}

TEST(SelfPatches, ARoundBallLeavesNoPairsWithinItself) {
  // What culling within patches alone left on a ball, every step: the pairs across the seams
  // between its patches, which neighbouring patches flat as one remove.
  const Ball ball(0.3f);
  const std::vector<Vec3>& positions = ball.positions;
  PatchFlatness flatness;
  updateFlatPatches(ball.geometry, positions, positions, flatness);
  std::vector<Box3> boxes;
  for (const Triangle& t : ball.geometry.triangleVertices) {
    Box3 box;
    for (Index v : t) box.extend(positions[v]);
    boxes.push_back(Box3(box.min().array() - 0.001f, box.max().array() + 0.001f));  // the skin
  }
  const BroadPhaseInput input = ball.geometry.broadPhaseInput(boxes, &flatness);
  BroadPhaseInput withinPatches = input;
  withinPatches.patchFlatWith = {};
  EXPECT_GT(definitionPairs(withinPatches).size(), 100u);
  EXPECT_EQ(definitionPairs(input).size(), 0u);
  for (BroadPhaseKind kind : kBroadPhaseKinds)
    EXPECT_EQ(candidates(kind, input).size(), 0u) << broadPhaseName(kind);
}

TEST(SelfPatches, CullingKeepsEveryPairThatCrossesOnCrumpledSheets) {
  // The theorem the culling rests on, against brute force: no pair of triangles that cross is
  // lost, on sheets crumpled until they pass through themselves, whichever broad phase runs.
  std::mt19937 rng(7);
  std::size_t crossing = 0, culled = 0, flatPatches = 0, culledAcross = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Sheet sheet(20);
    const Scalar amplitude = Scalar(0.05) + Scalar(0.05) * Scalar(trial);
    const std::vector<Vec3> shape = sheet.crumpled(rng, amplitude);
    PatchFlatness flatness;
    updateFlatPatches(sheet.geometry, shape, shape, flatness);
    flatPatches += count(flatness.flat);
    const std::vector<Box3> boxes = sheet.boxes(shape, shape);
    const BroadPhaseInput input = sheet.geometry.broadPhaseInput(boxes, &flatness);
    const std::vector<TrianglePair> expected = crossingPairs(sheet.geometry, shape);
    crossing += expected.size();
    culled += definitionPairs(sheet.geometry.broadPhaseInput(boxes)).size() -
              definitionPairs(input).size();
    BroadPhaseInput withinPatches = input;  // without the culling across neighbours
    withinPatches.patchFlatWith = {};
    culledAcross += definitionPairs(withinPatches).size() - definitionPairs(input).size();
    for (BroadPhaseKind kind : kBroadPhaseKinds) {
      const std::vector<TrianglePair> found = candidates(kind, input);
      EXPECT_EQ(found, definitionPairs(input)) << broadPhaseName(kind) << ", trial " << trial;
      for (const TrianglePair& pair : expected)
        EXPECT_TRUE(std::binary_search(found.begin(), found.end(), pair))
            << broadPhaseName(kind) << ", trial " << trial << ": crossing pair (" << pair.first
            << ", " << pair.second << ") culled";
    }
  }
  // Not vacuous: the sheets did cross themselves, and the culling did drop pairs.
  EXPECT_GT(crossing, 100u);
  EXPECT_GT(flatPatches, 0u);
  EXPECT_GT(culled, 1000u);
  EXPECT_GT(culledAcross, 100u);
}

TEST(SelfPatches, ThePairCacheStaysExactWhilePatchesTurnFlatAndBack) {
  // A sheet crumpling and smoothing out again, step by step: patches turn flat and back, and
  // the pairs within each come and go. The cache must follow, for every broad phase.
  const Sheet sheet(16);
  std::mt19937 rng(3);
  std::vector<std::vector<Vec3>> frames;
  const std::vector<Vec3> target = sheet.crumpled(rng, Scalar(0.5));
  constexpr int kSteps = 40;
  for (int step = 0; step <= kSteps; ++step) {
    const Scalar s = Scalar(0.5 - 0.5 * std::cos(2 * 3.14159265 * step / kSteps));  // 0 → 1 → 0
    std::vector<Vec3> shape = sheet.rest;
    for (std::size_t v = 0; v < shape.size(); ++v) shape[v] += s * (target[v] - sheet.rest[v]);
    frames.push_back(std::move(shape));
  }
  for (BroadPhaseKind kind : kBroadPhaseKinds) {
    const auto broadPhase = makeBroadPhase(kind);
    PairCache cache;
    std::vector<TrianglePair> pairs;
    PatchFlatness flatness;
    std::vector<std::uint8_t> before, beforeWith;
    std::size_t turned = 0, turnedWith = 0;
    for (int step = 1; step <= kSteps; ++step) {
      updateFlatPatches(sheet.geometry, frames[step - 1], frames[step], flatness);
      if (!before.empty()) {
        for (std::size_t p = 0; p < before.size(); ++p) turned += flatness.flat[p] != before[p];
        for (std::size_t k = 0; k < beforeWith.size(); ++k)
          turnedWith += flatness.flatWith[k] != beforeWith[k];
      }
      before = flatness.flat;
      beforeWith = flatness.flatWith;
      const std::vector<Box3> boxes = sheet.boxes(frames[step - 1], frames[step]);
      const BroadPhaseInput input = sheet.geometry.broadPhaseInput(boxes, &flatness);
      cache.findPairs(*broadPhase, input, pairs);
      ASSERT_EQ(pairs, definitionPairs(input)) << broadPhaseName(kind) << ", step " << step;
    }
    EXPECT_GE(turned, 4u) << broadPhaseName(kind);
    EXPECT_GE(turnedWith, 4u) << broadPhaseName(kind);
  }
}

}  // namespace
}  // namespace softbake
