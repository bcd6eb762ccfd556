// Completeness of the broad phases: on random triangle soups and on deforming, overlapping
// icospheres, every broad phase returns exactly brute force's pairs, and brute force returns
// exactly what the definition in core/broad_phase/broad_phase.hpp says.

#include "core/broad_phase/broad_phase.hpp"
#include "core/broad_phase/pair_cache.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <ostream>
#include <random>
#include <string>

#include "core/broad_phase/bvh.hpp"
#include "core/broad_phase/sbhash.hpp"
#include "core/broad_phase/spatial_hash.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/text.hpp"
#include "tests/core/allocation_counter.hpp"
#include "tests/support/definition_pairs.hpp"

namespace softbake {

void PrintTo(const TrianglePair& pair, std::ostream* out) {
  *out << "(" << pair.first << ", " << pair.second << ")";
}

namespace {

using test::definitionPairs;

constexpr BroadPhaseKind kFastKinds[] = {BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash,
                                         BroadPhaseKind::Bvh};

/// Surfaces, triangles and boxes in the layout BroadPhaseInput reads; owns what the spans view.
struct Soup {
  std::vector<Vec3> positions;
  std::vector<Triangle> triangles;
  std::vector<Index> triangleSurface;
  std::vector<CollisionSurface> surfaces;
  std::vector<std::array<Index, 2>> surfaceVertices;  ///< per surface: [first, end) in positions
  std::vector<Box3> boxes;

  /// Appends a surface; `surfaceTriangles` index `surfacePositions`.
  void addSurface(const std::vector<Vec3>& surfacePositions,
                  const std::vector<Triangle>& surfaceTriangles, bool moving, bool selfCollision) {
    const Index base = Index(positions.size());
    positions.insert(positions.end(), surfacePositions.begin(), surfacePositions.end());
    surfaceVertices.push_back({base, Index(positions.size())});
    surfaces.push_back(
        {Index(triangles.size()), Index(surfaceTriangles.size()), moving, selfCollision});
    for (const Triangle& t : surfaceTriangles) {
      triangles.push_back({base + t[0], base + t[1], base + t[2]});
      triangleSurface.push_back(Index(surfaces.size() - 1));
    }
  }

  /// Each triangle's box: its vertices, grown by `margin` on every side.
  void computeBoxes(Scalar margin = 0) {
    boxes.resize(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      Box3 box(positions[triangles[t][0]]);
      box.extend(positions[triangles[t][1]]);
      box.extend(positions[triangles[t][2]]);
      boxes[t] = Box3(box.min().array() - margin, box.max().array() + margin);
    }
  }

  /// Applies `move` to every vertex of a moving surface.
  template <class Move>
  void moveMovingVertices(Move&& move) {
    for (std::size_t s = 0; s < surfaces.size(); ++s)
      if (surfaces[s].moving)
        for (Index v = surfaceVertices[s][0]; v < surfaceVertices[s][1]; ++v) move(positions[v]);
  }

  /// Shakes the vertices of moving surfaces by up to `amplitude` per axis; recomputes the boxes.
  void jitterMoving(std::mt19937& rng, Scalar amplitude, Scalar margin = 0) {
    std::uniform_real_distribution<Scalar> noise(-amplitude, amplitude);
    moveMovingVertices([&](Vec3& p) { p += Vec3(noise(rng), noise(rng), noise(rng)); });
    computeBoxes(margin);
  }

  BroadPhaseInput input() const {
    return {.triangleBox = boxes,
            .triangleVertices = triangles,
            .triangleSurface = triangleSurface,
            .surfaces = surfaces};
  }
};

std::vector<TrianglePair> run(BroadPhase& broadPhase, const BroadPhaseInput& input) {
  std::vector<TrianglePair> pairs;
  broadPhase.findPairs(input, pairs);
  return pairs;
}

std::vector<TrianglePair> brutePairs(const BroadPhaseInput& input) {
  return run(*makeBroadPhase(BroadPhaseKind::BruteForce), input);
}

/// The first pair brute force has and `actual` lacks, and the first the other way round.
std::string firstDifference(const std::vector<TrianglePair>& expected,
                            const std::vector<TrianglePair>& actual) {
  std::vector<TrianglePair> missing, extra;
  std::set_difference(expected.begin(), expected.end(), actual.begin(), actual.end(),
                      std::back_inserter(missing));
  std::set_difference(actual.begin(), actual.end(), expected.begin(), expected.end(),
                      std::back_inserter(extra));
  std::string text = cat(expected.size(), " expected, ", actual.size(), " found, ", missing.size(),
                         " missing, ", extra.size(), " extra");
  if (!missing.empty())
    text += cat("; first missing (", missing[0].first, ", ", missing[0].second, ")");
  if (!extra.empty()) text += cat("; first extra (", extra[0].first, ", ", extra[0].second, ")");
  if (!std::is_sorted(actual.begin(), actual.end())) text += "; not sorted";
  return text;
}

/// Every fast kind at every subdivision level agrees with brute force on `soup`.
void expectAllKindsMatchBrute(const Soup& soup, const std::string& scene) {
  const BroadPhaseInput input = soup.input();
  const std::vector<TrianglePair> expected = brutePairs(input);
  for (int levels = 1; levels <= 4; ++levels) {
    for (BroadPhaseKind kind : kFastKinds) {
      if (kind != BroadPhaseKind::Sbhash && levels > 1) continue;  // only sbhash has levels
      const auto broadPhase = makeBroadPhase(kind, {levels});
      const std::vector<TrianglePair> actual = run(*broadPhase, input);
      EXPECT_EQ(actual, expected) << scene << ", " << broadPhaseName(kind) << ", L=" << levels
                                  << ": " << firstDifference(expected, actual);
    }
  }
}

/// A random soup: several surfaces, some static, some self-colliding. Triangles range from a point
/// to the size of the scene, and about half share an edge with an earlier triangle of their
/// surface. With `snap`, coordinates sit on a coarse lattice so that many boxes touch exactly.
Soup randomSoup(std::mt19937& rng, Scalar scale, const Vec3& offset, bool snap = false) {
  std::uniform_real_distribution<Scalar> unit(0, 1);
  std::uniform_int_distribution<int> surfaceCount(2, 6), triangleCount(1, 120);
  Soup soup;
  const int surfaces = surfaceCount(rng);
  for (int s = 0; s < surfaces; ++s) {
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
    const Vec3 center = Vec3(unit(rng), unit(rng), unit(rng)) * 8;
    auto point = [&](const Vec3& near, Scalar size) {
      Vec3 p = near + (Vec3(unit(rng), unit(rng), unit(rng)) - Vec3::Constant(0.5)) * size;
      if (snap) p = (p * 4).array().round() / 4;
      return p;
    };
    const int count = triangleCount(rng);
    for (int t = 0; t < count; ++t) {
      // log-uniform from 1e-5 to 10, and now and then a single point
      const Scalar size = unit(rng) < 0.05 ? 0 : Scalar(std::pow(10.0, -5 + 6 * unit(rng)));
      const Index base = Index(positions.size());
      if (!triangles.empty() && unit(rng) < 0.5) {
        const Triangle& earlier = triangles[std::size_t(unit(rng) * Scalar(triangles.size() - 1))];
        positions.push_back(point(positions[earlier[0]], size));
        triangles.push_back({earlier[0], earlier[1], base});
      } else {
        const Vec3 at = point(center, 6);
        positions.push_back(point(at, size));
        positions.push_back(point(at, size));
        positions.push_back(point(at, size));
        triangles.push_back({base, base + 1, base + 2});
      }
    }
    for (Vec3& p : positions) p = p * scale + offset;
    soup.addSurface(positions, triangles, unit(rng) < 0.7, unit(rng) < 0.5);
  }
  soup.computeBoxes(unit(rng) < 0.5 ? Scalar(0) : Scalar(1e-3) * scale);
  return soup;
}

/// Icospheres of radius `scale` whose centres lie closer than a diameter, randomly dented so they
/// fold into themselves, and (with `ground`) a static ground grid under them.
Soup icosphereScene(std::mt19937& rng, Scalar scale, int subdivisions, int bodies, bool ground) {
  std::uniform_real_distribution<Scalar> unit(0, 1);
  Soup soup;
  for (int b = 0; b < bodies; ++b) {
    const Vec3f center = Vec3f(1.3f * float(b), 0.3f * float(b % 2), 0.2f * float(b % 3));
    const TriangleMesh mesh = makeIcosphere(subdivisions, 1.0f, center);
    std::vector<Vec3> positions;
    for (const Vec3f& p : mesh.positions) {
      Vec3 q = p.cast<Scalar>();
      if (unit(rng) < 0.1) q = center.cast<Scalar>() + (q - center.cast<Scalar>()) * unit(rng);
      positions.push_back(q * scale);
    }
    soup.addSurface(positions, mesh.triangles, b != bodies - 1 || !ground, b % 2 == 0);
  }
  if (ground) {
    constexpr int kGrid = 8;
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
    for (int z = 0; z <= kGrid; ++z)
      for (int x = 0; x <= kGrid; ++x)
        positions.push_back(Vec3(Scalar(x - kGrid / 2), Scalar(-0.8), Scalar(z - kGrid / 2)) *
                            scale);
    for (int z = 0; z < kGrid; ++z)
      for (int x = 0; x < kGrid; ++x) {
        const Index a = Index(z * (kGrid + 1) + x), c = a + kGrid + 1;
        triangles.push_back({a, c, a + 1});
        triangles.push_back({a + 1, c, c + 1});
      }
    soup.addSurface(positions, triangles, false, false);
  }
  soup.computeBoxes(Scalar(0.01) * scale);
  return soup;
}

TEST(BroadPhase, NamesRoundTrip) {
  for (BroadPhaseKind kind : {BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash,
                              BroadPhaseKind::Bvh, BroadPhaseKind::BruteForce}) {
    BroadPhaseKind parsed{};
    ASSERT_TRUE(parseBroadPhase(broadPhaseName(kind), parsed)) << broadPhaseName(kind);
    EXPECT_EQ(parsed, kind);
    EXPECT_EQ(makeBroadPhase(kind)->kind(), kind);
  }
  BroadPhaseKind unchanged = BroadPhaseKind::Bvh;
  EXPECT_FALSE(parseBroadPhase("octree", unchanged));
  EXPECT_EQ(unchanged, BroadPhaseKind::Bvh);
  EXPECT_EQ(broadPhaseName(BroadPhaseKind::Sbhash), "sbhash");
  EXPECT_EQ(broadPhaseName(BroadPhaseKind::SpatialHash), "spatialhash");
}

TEST(BroadPhase, EligibilityFollowsSurfaceKindsAndSharedVertices) {
  Soup soup;
  const std::vector<Vec3> points = {{0, 0, 0}, {1, 0, 0},     {1, 1, 0},
                                    {0, 1, 0}, {0.5, 0.5, 0}, {0.6, 0.4, 0}};
  // 1 shares vertex 0 and 2 with 0; 2 shares vertex 1 with 0 and nothing with 1.
  const std::vector<Triangle> mesh = {{0, 1, 2}, {2, 3, 0}, {4, 5, 1}};
  soup.addSurface(points, mesh, true, true);    // triangles 0..2: moving, self-colliding
  soup.addSurface(points, mesh, true, false);   // 3..5: moving
  soup.addSurface(points, mesh, false, false);  // 6..8: static
  soup.addSurface(points, mesh, false, false);  // 9..11: static
  soup.addSurface(points, mesh, false, true);   // 12..14: static, self-colliding
  soup.computeBoxes();
  const BroadPhaseInput input = soup.input();
  EXPECT_FALSE(pairEligible(input, 0, 1));  // shared vertices
  EXPECT_FALSE(pairEligible(input, 0, 2));  // one shared vertex is enough
  EXPECT_TRUE(pairEligible(input, 1, 2));   // self-colliding, nothing shared
  EXPECT_FALSE(pairEligible(input, 4, 5));  // no self-collision
  EXPECT_TRUE(pairEligible(input, 0, 3));   // two moving surfaces
  EXPECT_TRUE(pairEligible(input, 3, 6));   // moving against static
  EXPECT_TRUE(pairEligible(input, 6, 3));
  EXPECT_FALSE(pairEligible(input, 6, 9));  // two static surfaces
  EXPECT_FALSE(pairEligible(input, 7, 8));
  EXPECT_TRUE(pairEligible(input, 13, 14));  // static but self-colliding
}

TEST(BroadPhase, BruteForceEqualsTheDefinitionOnRandomSoups) {
  std::mt19937 rng(11);
  for (int round = 0; round < 20; ++round) {
    const Soup soup = randomSoup(rng, 1, Vec3::Zero(), round % 4 == 0);
    const BroadPhaseInput input = soup.input();
    const std::vector<TrianglePair> expected = definitionPairs(input);
    const std::vector<TrianglePair> actual = brutePairs(input);
    EXPECT_EQ(actual, expected) << "round " << round << ": " << firstDifference(expected, actual);
  }
}

TEST(BroadPhase, EveryKindMatchesBruteOnRandomSoups) {
  std::mt19937 rng(7);
  const Scalar scales[] = {Scalar(1e-3), 1, Scalar(1e3)};
  for (int round = 0; round < 12; ++round) {
    for (Scalar scale : scales) {
      const Vec3 offset = round % 3 == 0 ? Vec3(Vec3(-50, 20, 7) * scale) : Vec3(Vec3::Zero());
      const Soup soup = randomSoup(rng, scale, offset, round % 4 == 1);
      expectAllKindsMatchBrute(soup, cat("round ", round, ", scale ", scale));
    }
  }
}

TEST(BroadPhase, EveryKindMatchesBruteOnDentedOverlappingIcospheres) {
  std::mt19937 rng(3);
  for (Scalar scale : {Scalar(0.01), Scalar(1), Scalar(100)}) {
    for (bool ground : {false, true}) {
      const Soup soup = icosphereScene(rng, scale, 2, 4, ground);
      const std::vector<TrianglePair> expected = brutePairs(soup.input());
      ASSERT_FALSE(expected.empty());
      expectAllKindsMatchBrute(soup, cat("scale ", scale, ground ? ", ground" : ""));
    }
  }
}

TEST(BroadPhase, EveryKindStaysExactWhileBodiesDeformStepAfterStep) {
  // One broad phase object per kind, reused: the refit path, cached static leaves and trees, and
  // buffers that keep their capacity are what a simulation actually runs.
  std::mt19937 rng(5);
  Soup soup = icosphereScene(rng, 1, 3, 3, true);
  std::vector<std::unique_ptr<BroadPhase>> broadPhases;
  for (int levels = 1; levels <= 4; ++levels)
    broadPhases.push_back(makeBroadPhase(BroadPhaseKind::Sbhash, {levels}));
  broadPhases.push_back(makeBroadPhase(BroadPhaseKind::SpatialHash));
  broadPhases.push_back(makeBroadPhase(BroadPhaseKind::Bvh));
  for (int step = 0; step < 6; ++step) {
    const std::vector<TrianglePair> expected = brutePairs(soup.input());
    for (std::size_t k = 0; k < broadPhases.size(); ++k) {
      const std::vector<TrianglePair> actual = run(*broadPhases[k], soup.input());
      EXPECT_EQ(actual, expected) << "step " << step << ", "
                                  << broadPhaseName(broadPhases[k]->kind()) << " #" << k << ": "
                                  << firstDifference(expected, actual);
    }
    // Static surfaces (a ball and the ground) are cut into leaves on the first call only.
    const auto& boxHash = static_cast<const SbhashBroadPhase&>(*broadPhases[0]);
    const auto moving = std::size_t(std::count_if(soup.surfaces.begin(), soup.surfaces.end(),
                                                  [](const auto& s) { return s.moving; }));
    EXPECT_EQ(boxHash.lastStats().rebuiltSurfaces, step == 0 ? soup.surfaces.size() : moving);
    // Squash, shift and shake the moving bodies; the static ground stays (the contract).
    soup.moveMovingVertices([](Vec3& p) {
      p.y() = Scalar(0.95) * p.y() - Scalar(0.03);
      p.x() += Scalar(0.05);
    });
    soup.jitterMoving(rng, Scalar(0.02), Scalar(0.01));
  }
}

TEST(PairCache, GivesTheBroadPhasesExactPairsWhileBodiesCreepAndJump) {
  // Small moves stay inside the grown boxes and reuse the cached pairs; a jump forces a rebuild.
  // Either way the pairs must equal brute force on the current boxes, in the same order.
  std::mt19937 rng(9);
  Soup soup = icosphereScene(rng, 1, 3, 3, true);
  for (BroadPhaseKind kind : {BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash,
                              BroadPhaseKind::Bvh, BroadPhaseKind::BruteForce}) {
    Soup scene = soup;
    std::unique_ptr<BroadPhase> broadPhase = makeBroadPhase(kind);
    PairCache cache;
    std::vector<TrianglePair> pairs;
    constexpr int kSteps = 40;
    for (int step = 0; step < kSteps; ++step) {
      cache.findPairs(*broadPhase, scene.input(), pairs);
      const std::vector<TrianglePair> expected = brutePairs(scene.input());
      ASSERT_EQ(pairs, expected) << broadPhaseName(kind) << ", step " << step << ": "
                                 << firstDifference(expected, pairs);
      const Scalar move = step % 10 == 9 ? Scalar(0.2) : Scalar(0.0005);
      scene.moveMovingVertices([&](Vec3& p) { p.x() += move; });
      scene.jitterMoving(rng, Scalar(0.0005), Scalar(0.01));
    }
    // The first call and the three jumps seen before the last call rebuild; creeping reuses.
    EXPECT_GE(cache.rebuilds(), 4u) << broadPhaseName(kind);
    EXPECT_LE(cache.rebuilds(), std::size_t(kSteps / 4)) << broadPhaseName(kind);
    // Only the tree can find the pairs of a few triangles alone; the others rebuild instead.
    if (kind != BroadPhaseKind::Bvh) {
      EXPECT_EQ(cache.updates(), 0u) << broadPhaseName(kind);
    }
  }
}

TEST(PairCache, FindsAgainOnlyTheTrianglesThatLeftTheirGrownBoxes) {
  // One body creeps into the others a little each step, its vertices shaken, so a few of its
  // triangles leave their grown boxes on most steps: their pairs are found again alone, and the
  // list must still equal brute force on the current boxes, in order, on every step.
  std::mt19937 rng(17);
  Soup scene = icosphereScene(rng, 1, 2, 3, true);
  std::uniform_real_distribution<Scalar> noise(Scalar(-0.006), Scalar(0.006));
  BvhBroadPhase broadPhase;
  PairCache cache;
  std::vector<TrianglePair> pairs;
  for (int step = 0; step < 60; ++step) {
    cache.findPairs(broadPhase, scene.input(), pairs);
    const std::vector<TrianglePair> expected = brutePairs(scene.input());
    ASSERT_EQ(pairs, expected) << "step " << step << ": " << firstDifference(expected, pairs);
    for (Index v = scene.surfaceVertices[0][0]; v < scene.surfaceVertices[0][1]; ++v)
      scene.positions[v] += Vec3(Scalar(0.004) + noise(rng), noise(rng), noise(rng));
    scene.computeBoxes(Scalar(0.01));
  }
  EXPECT_GT(cache.updates(), 2 * cache.rebuilds());
  RecordProperty("updates", int(cache.updates()));
  RecordProperty("rebuilds", int(cache.rebuilds()));
}

TEST(PairCache, NarrowsItsMarginWhereLongSliversCrowd) {
  // Coaxial tubes fitted 3 mm apart, each side a ring of slivers 50 m long and 0.1 m wide, as a
  // CAD assembly's cylinders are meshed: a margin from the mean box (12 m) would cache every pair
  // of tubes, 30 times the pairs that overlap. The cache narrows its margin at its first rebuild
  // and stays exact, in order, while the tubes creep.
  Soup soup;
  constexpr int kSegments = 64;
  for (int tube = 0; tube < 6; ++tube) {
    const Scalar radius = Scalar(1 + 0.003 * tube);
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
    for (int end = 0; end < 2; ++end)
      for (int k = 0; k < kSegments; ++k) {
        const double angle = 2 * 3.14159265358979 * k / kSegments;
        positions.push_back(Vec3(radius * Scalar(std::cos(angle)), radius * Scalar(std::sin(angle)),
                                 Scalar(50 * end)));
      }
    for (Index k = 0; k < kSegments; ++k) {
      const Index next = (k + 1) % kSegments;
      triangles.push_back({k, next, kSegments + k});
      triangles.push_back({next, kSegments + next, kSegments + k});
    }
    soup.addSurface(positions, triangles, true, false);
  }
  soup.computeBoxes(Scalar(0.001));
  BvhBroadPhase broadPhase;
  PairCache cache;
  std::vector<TrianglePair> pairs;
  std::mt19937 rng(31);
  for (int step = 0; step < 12; ++step) {
    cache.findPairs(broadPhase, soup.input(), pairs);
    const std::vector<TrianglePair> expected = brutePairs(soup.input());
    ASSERT_EQ(pairs, expected) << "step " << step << ": " << firstDifference(expected, pairs);
    if (step == 0) {
      EXPECT_LE(cache.cachedPairs(),
                PairCache::kMostCachedPerPair * std::max<std::size_t>(expected.size(), 1024));
      RecordProperty("cached", int(cache.cachedPairs()));
      RecordProperty("exact", int(expected.size()));
    }
    soup.jitterMoving(rng, Scalar(0.0002), Scalar(0.001));
  }
}

TEST(Bvh, PairsInvolvingSomeTrianglesAreBruteForcesPairsThatInvolveThem) {
  // After a full search, some triangles' boxes move (and others' do not, as the pair cache
  // promises); the tree takes in their new boxes and must list exactly the pairs brute force finds
  // on the new boxes that involve them, sorted. Rounds of many moved triangles also pass the
  // point where the tree is refitted instead.
  std::mt19937 rng(23);
  for (int scene = 0; scene < 6; ++scene) {
    Soup soup = scene % 2 ? randomSoup(rng, 1, Vec3::Zero()) : icosphereScene(rng, 1, 2, 3, true);
    BvhBroadPhase broadPhase;
    run(broadPhase, soup.input());
    std::uniform_real_distribution<Scalar> unit(0, 1);
    for (int round = 0; round < 8; ++round) {
      const Scalar share = round % 4 == 3 ? Scalar(0.5) : Scalar(0.03);
      std::vector<Index> moved;
      for (Index t = 0; t < soup.triangles.size(); ++t)
        if (soup.surfaces[soup.triangleSurface[t]].moving && unit(rng) < share) moved.push_back(t);
      for (Index t : moved) {
        const Vec3 shift = (Vec3(unit(rng), unit(rng), unit(rng)) - Vec3::Constant(0.5)) *
                           Scalar(round % 2 ? 0.5 : 0.05);
        soup.boxes[t].translate(shift);
      }
      std::vector<TrianglePair> actual;
      ASSERT_TRUE(broadPhase.findPairsInvolving(soup.input(), moved, actual));
      std::vector<TrianglePair> expected;
      for (const TrianglePair& pair : brutePairs(soup.input()))
        if (std::binary_search(moved.begin(), moved.end(), pair.first) ||
            std::binary_search(moved.begin(), moved.end(), pair.second))
          expected.push_back(pair);
      ASSERT_EQ(actual, expected) << "scene " << scene << ", round " << round << ": "
                                  << firstDifference(expected, actual);
    }
  }
}

TEST(BroadPhase, OnlyTheTreeFindsThePairsOfSomeTrianglesAlone) {
  std::mt19937 rng(5);
  const Soup soup = icosphereScene(rng, 1, 2, 2, false);
  const std::vector<Index> some{0, 1, 2};
  for (BroadPhaseKind kind : kBroadPhaseKinds) {
    const std::unique_ptr<BroadPhase> broadPhase = makeBroadPhase(kind);
    std::vector<TrianglePair> pairs;
    // Before any full search there is no tree to take the boxes in.
    EXPECT_FALSE(broadPhase->findPairsInvolving(soup.input(), some, pairs));
    run(*broadPhase, soup.input());
    EXPECT_EQ(broadPhase->findPairsInvolving(soup.input(), some, pairs),
              kind == BroadPhaseKind::Bvh)
        << broadPhaseName(kind);
  }
}

TEST(BroadPhase, EveryKindGivesTheSameAnswerOnOneThread) {
  std::mt19937 rng(9);
  const Soup soup = icosphereScene(rng, 1, 3, 3, true);
  for (BroadPhaseKind kind : kFastKinds) {
    const std::vector<TrianglePair> many = run(*makeBroadPhase(kind), soup.input());
    std::vector<TrianglePair> one;
    {
      tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
      one = run(*makeBroadPhase(kind), soup.input());
    }
    EXPECT_EQ(one, many) << broadPhaseName(kind);
  }
}

TEST(BroadPhase, SurfacesFarApartGiveNoPairs) {
  Soup soup;
  for (int b = 0; b < 2; ++b) {
    const TriangleMesh mesh = makeIcosphere(2, 1.0f, Vec3f(10.0f * float(b), 0, 0));
    std::vector<Vec3> positions;
    for (const Vec3f& p : mesh.positions) positions.push_back(p.cast<Scalar>());
    soup.addSurface(positions, mesh.triangles, true, false);
  }
  soup.computeBoxes(Scalar(0.01));
  for (BroadPhaseKind kind : {BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash,
                              BroadPhaseKind::Bvh, BroadPhaseKind::BruteForce}) {
    std::vector<TrianglePair> pairs = {{0, 1}};  // replaced, not appended to
    const auto broadPhase = makeBroadPhase(kind);
    broadPhase->findPairs(soup.input(), pairs);
    EXPECT_TRUE(pairs.empty()) << broadPhaseName(kind) << ": " << pairs.size() << " pairs";
    if (kind == BroadPhaseKind::Sbhash) {  // the surface-box level culls both bodies outright
      EXPECT_EQ(static_cast<SbhashBroadPhase&>(*broadPhase).lastStats().activeSurfaces, 0u);
    }
  }
}

TEST(BroadPhase, EmptyInputAndEmptySurfacesGiveNoPairs) {
  Soup empty;
  Soup withEmptySurfaces;
  withEmptySurfaces.addSurface({}, {}, true, true);
  withEmptySurfaces.addSurface({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, true, true);
  withEmptySurfaces.addSurface({}, {}, false, false);
  withEmptySurfaces.computeBoxes();
  for (const Soup* soup : {&empty, &withEmptySurfaces})
    for (BroadPhaseKind kind : {BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash,
                                BroadPhaseKind::Bvh, BroadPhaseKind::BruteForce}) {
      std::vector<TrianglePair> pairs = {{0, 1}};
      makeBroadPhase(kind)->findPairs(soup->input(), pairs);
      EXPECT_TRUE(pairs.empty()) << broadPhaseName(kind);
    }
}

TEST(BroadPhase, WarmedUpFindPairsAllocatesNothing) {
  std::mt19937 rng(13);
  const Soup soup = icosphereScene(rng, 1, 3, 3, true);
  for (BroadPhaseKind kind : {BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash,
                              BroadPhaseKind::Bvh, BroadPhaseKind::BruteForce}) {
    const auto broadPhase = makeBroadPhase(kind);
    std::vector<TrianglePair> pairs;
    broadPhase->findPairs(soup.input(), pairs);
    const test::CountedAllocations counted;
    broadPhase->findPairs(soup.input(), pairs);
    EXPECT_EQ(counted.allocations(), 0) << broadPhaseName(kind);
  }
}

TEST(BoxHash, CellSizeCoversEveryLeafBox) {
  std::mt19937 rng(17);
  for (int levels = 1; levels <= 4; ++levels) {
    const Soup soup = icosphereScene(rng, 1, 3, 4, true);
    SbhashBroadPhase broadPhase(levels);
    run(broadPhase, soup.input());
    const SbhashStats& stats = broadPhase.lastStats();
    ASSERT_EQ(stats.leaves, broadPhase.lastLeafBoxes().size());
    ASSERT_GT(stats.leaves, 0u);
    EXPECT_GT(stats.candidateLeafPairs, 0u);
    EXPECT_EQ(stats.activeSurfaces, soup.surfaces.size());
    for (const Box3& leaf : broadPhase.lastLeafBoxes()) {
      ASSERT_FALSE(leaf.isEmpty());
      for (int axis = 0; axis < 3; ++axis)
        ASSERT_GE(stats.cellSize[axis], double(leaf.max()[axis]) - double(leaf.min()[axis]))
            << "L=" << levels << ", axis " << axis;
    }
    // No leaf is larger than its surface box cut 2^L ways (clipping to the cell).
    EXPECT_LE(stats.maxLeafExtent.maxCoeff(), 10.0 / (1 << levels));
  }
}

TEST(BoxHash, OverlappingBoxesWithinTheCellSizeShareACornerCell) {
  // The lemma the box hash stands on: per axis, intervals no longer than the cell that overlap
  // have an endpoint each in one cell, so the boxes have a corner each in one cell.
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int round = 0; round < 20000; ++round) {
    const double far = round % 2 ? 1e4 : 0;  // far from the origin, floats round coarsely
    const double extent = std::pow(10.0, -3 + 4 * unit(rng));
    auto randomBox = [&](const Vec3d& near) {
      Vec3d lo, hi;
      for (int axis = 0; axis < 3; ++axis) {
        // a quarter of the boxes as long as allowed, the rest random
        const double length = unit(rng) < 0.25 ? extent : extent * unit(rng);
        lo[axis] = near[axis] + (unit(rng) - 0.5) * extent;
        hi[axis] = lo[axis] + length;
      }
      return Box3(lo.cast<Scalar>(), hi.cast<Scalar>());
    };
    const Box3 a = randomBox(Vec3d::Constant(far));
    Box3 b = randomBox(a.min().cast<double>());
    if (round % 5 == 0) {  // touching exactly, face to face
      const double length = std::min(extent, double(b.max().x()) - double(b.min().x()));
      b.min().x() = a.max().x();
      b.max().x() = Scalar(double(a.max().x()) + length);
    }
    if (!a.intersects(b)) continue;
    auto extent3 = [](const Box3& box) -> Vec3d {
      return box.max().cast<double>() - box.min().cast<double>();
    };
    const Vec3d maxExtent = extent3(a).cwiseMax(extent3(b));
    const Box3 bounds = a.merged(b);
    const BoxHashGrid grid = BoxHashGrid::fit(bounds, maxExtent);
    bool shared = false;
    for (int ca = 0; ca < 8 && !shared; ++ca)
      for (int cb = 0; cb < 8 && !shared; ++cb)
        shared =
            grid.cell(a.corner(Box3::CornerType(ca))) == grid.cell(b.corner(Box3::CornerType(cb)));
    ASSERT_TRUE(shared) << "round " << round;
  }
}

TEST(SpatialHash, HugeStaticTrianglesStayWithinTheEntryBound) {
  // A ground of two triangles, 10^4 times the size of a ball's triangles: in one grid it would
  // cover ~10^8 cells. Levels keep every triangle to at most 64 entries.
  std::mt19937 rng(23);
  Soup soup = icosphereScene(rng, 1, 3, 2, false);
  const Scalar half = 5000;
  const Scalar low = Scalar(-0.9), high = Scalar(0.5);
  soup.addSurface({{-half, low, -half}, {half, low, -half}, {half, low, half}, {-half, low, half}},
                  {{0, 2, 1}, {0, 3, 2}}, false, false);
  // and a moving sheet as big, so the huge triangles have moving partners too
  soup.addSurface({{-half, high, -half}, {half, high, -half}, {0, high, half}}, {{0, 2, 1}}, true,
                  false);
  soup.computeBoxes(Scalar(0.01));
  SpatialHashBroadPhase broadPhase;
  const std::vector<TrianglePair> actual = run(broadPhase, soup.input());
  const std::vector<TrianglePair> expected = brutePairs(soup.input());
  EXPECT_EQ(actual, expected) << firstDifference(expected, actual);
  EXPECT_LE(broadPhase.lastStats().entries,
            soup.triangles.size() * SpatialHashBroadPhase::kMaxCellsPerAxis *
                SpatialHashBroadPhase::kMaxCellsPerAxis * SpatialHashBroadPhase::kMaxCellsPerAxis);
  EXPECT_GT(broadPhase.lastStats().levels, 1);
}

TEST(PairBuffers, MergeManyPairsIntoOneSortedListWithoutRepeats) {
  // Enough pairs for the parallel bucketed sort, some in several buffers, with indices from a
  // few dozen (one bucket) to a million: the same list as a comparison sort and std::unique.
  std::mt19937 rng(31);
  for (const Index range : {Index(40), Index(5000), Index(1'000'000)}) {
    std::uniform_int_distribution<Index> index(0, range - 1);
    broad_phase_detail::PairBuffers buffers;
    buffers.reset(37);
    std::vector<TrianglePair> all;
    for (int k = 0; k < 120'000; ++k) {
      Index a = index(rng), b = index(rng);
      if (a == b) continue;
      const TrianglePair pair{std::min(a, b), std::max(a, b)};
      buffers[std::size_t(k) % 37].push_back(pair);
      all.push_back(pair);
      if (k % 10 == 0) {  // the same pair found again from another chunk
        buffers[std::size_t(k + 5) % 37].push_back(pair);
        all.push_back(pair);
      }
    }
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    std::vector<TrianglePair> merged;
    buffers.mergeInto(merged);
    EXPECT_EQ(merged, all) << "indices below " << range << ": " << firstDifference(all, merged);
  }
}

TEST(Bvh, RebuildsWhenRefitLetsTheTreeGrowLoose) {
  std::mt19937 rng(29);
  Soup soup = icosphereScene(rng, 1, 3, 2, false);
  BvhBroadPhase broadPhase;
  run(broadPhase, soup.input());
  EXPECT_EQ(broadPhase.lastStats().rebuilds, 2u);  // the first call builds every tree
  soup.jitterMoving(rng, Scalar(0.001), Scalar(0.01));
  run(broadPhase, soup.input());
  EXPECT_EQ(broadPhase.lastStats().rebuilds, 0u);  // a small motion only refits
  // Scatter one body's vertices through its volume: neighbours in the tree are no longer near.
  std::shuffle(soup.positions.begin(), soup.positions.begin() + 642, rng);
  soup.computeBoxes(Scalar(0.01));
  const std::vector<TrianglePair> actual = run(broadPhase, soup.input());
  EXPECT_GE(broadPhase.lastStats().rebuilds, 1u);
  const std::vector<TrianglePair> expected = brutePairs(soup.input());
  EXPECT_EQ(actual, expected) << firstDifference(expected, actual);
}

}  // namespace
}  // namespace softbake
