// The multi-pass test (Mesit & Guha §2.3) on triangle pairs: analytic configurations on small
// integer coordinates (exact in float, so points are compared with ==), then random pairs against
// Möller's triangle–triangle test in double (tests/support/exact_geometry.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>

#include "core/collision/triangle_pair_intersection.hpp"
#include "tests/support/exact_geometry.hpp"

namespace softbake {
namespace {

// The right triangle with legs 8 on x and y, in the plane z = 0.
const TriangleCorners kFloor = {Vec3(0, 0, 0), Vec3(8, 0, 0), Vec3(0, 8, 0)};

TriangleCorners rotated(const TriangleCorners& t, int by) {
  return {t[by % 3], t[(by + 1) % 3], t[(by + 2) % 3]};
}

bool referenceIntersects(const TriangleCorners& first, const TriangleCorners& second) {
  return test::trianglesIntersect(test::toDouble(first), test::toDouble(second));
}

TEST(TrianglePair, CrossingTrianglesHitOnceEachWayOnTheIntersectionLine) {
  // Like two links of a chain: first (z = 0) meets the line y = z = 0 in x ∈ [−4, 4], second
  // (y = 0) in x ∈ [2, 10]. They share x ∈ [2, 4]: its end x = 4 is first's edge 1 crossing
  // second, its end x = 2 is second's edge 0 crossing first. The other crossings of the line,
  // x = −4 and x = 10, lie outside the other triangle; the remaining edges stay off the planes.
  const TriangleCorners first = {Vec3(-4, -4, 0), Vec3(12, -4, 0), Vec3(-4, 4, 0)};
  const TriangleCorners second = {Vec3(2, 0, -4), Vec3(2, 0, 4), Vec3(18, 0, -4)};
  TrianglePairHits hits;
  ASSERT_TRUE(intersectTrianglePair(first, second, hits));
  ASSERT_EQ(hits.firstCount, 1);
  ASSERT_EQ(hits.secondCount, 1);
  const SegmentTriangleHit& a = hits.firstEdges[0].hit;
  const SegmentTriangleHit& b = hits.secondEdges[0].hit;
  EXPECT_EQ(hits.firstEdges[0].edge, 1);
  EXPECT_EQ(a.t, Scalar(0.5));
  EXPECT_EQ(a.point, Vec3(4, 0, 0));
  EXPECT_EQ(a.barycentric, Vec3(0.375, 0.5, 0.125));  // of second's corners
  EXPECT_EQ(hits.secondEdges[0].edge, 0);
  EXPECT_EQ(b.t, Scalar(0.5));
  EXPECT_EQ(b.point, Vec3(2, 0, 0));
  EXPECT_EQ(b.barycentric, Vec3(0.125, 0.375, 0.5));  // of first's corners
  EXPECT_TRUE(referenceIntersects(first, second));
}

TEST(TrianglePair, CornerPokingThroughGivesTwoHitsOneWayAndNoneTheOther) {
  // The corner (2, 2, −2) pokes through the floor: edges 0 and 2 cross it at x = 1.5 and 2.5 on
  // the line y = 2, z = 0, the ends of the intersection segment. The floor's edges cross the
  // plane y = 2 at x = 6 and x = 0, outside the poking triangle.
  const TriangleCorners poker = {Vec3(2, 2, -2), Vec3(1, 2, 2), Vec3(3, 2, 2)};
  TrianglePairHits hits;
  ASSERT_TRUE(intersectTrianglePair(kFloor, poker, hits));
  EXPECT_EQ(hits.firstCount, 0);
  ASSERT_EQ(hits.secondCount, 2);
  EXPECT_EQ(hits.secondEdges[0].edge, 0);
  EXPECT_EQ(hits.secondEdges[0].hit.point, Vec3(1.5, 2, 0));
  EXPECT_EQ(hits.secondEdges[1].edge, 2);
  EXPECT_EQ(hits.secondEdges[1].hit.point, Vec3(2.5, 2, 0));
  EXPECT_TRUE(referenceIntersects(kFloor, poker));
}

TEST(TrianglePair, DisjointAndParallelTrianglesDoNotHit) {
  const std::array<TriangleCorners, 4> others = {{
      {Vec3(20, 0, -1), Vec3(24, 0, 1), Vec3(20, 4, 1)},  // crosses the floor's plane far away
      {Vec3(6, 6, -1), Vec3(7, 6, 1), Vec3(6, 7, 1)},     // crosses it just beyond the hypotenuse
      {Vec3(0, 0, 1), Vec3(8, 0, 1), Vec3(0, 8, 1)},      // parallel, above
      {Vec3(-8, -8, -1), Vec3(16, -8, -1), Vec3(-8, 16, -1)},  // parallel, below and larger
  }};
  for (const TriangleCorners& other : others) {
    TrianglePairHits hits;
    EXPECT_FALSE(intersectTrianglePair(kFloor, other, hits));
    EXPECT_EQ(hits.firstCount + hits.secondCount, 0);
    EXPECT_FALSE(referenceIntersects(kFloor, other));
  }
}

TEST(TrianglePair, CoplanarOverlapIsNotReportedButTheReferenceSeesIt) {
  // Documented limitation (triangle_pair_intersection.hpp): in-plane edges cross nothing.
  const TriangleCorners shifted = {Vec3(1, 1, 0), Vec3(9, 1, 0), Vec3(1, 9, 0)};
  TrianglePairHits hits;
  EXPECT_FALSE(intersectTrianglePair(kFloor, shifted, hits));
  EXPECT_TRUE(referenceIntersects(kFloor, shifted));
  EXPECT_TRUE(referenceIntersects(kFloor, kFloor));
  const TriangleCorners apart = {Vec3(9, 9, 0), Vec3(12, 9, 0), Vec3(9, 12, 0)};
  EXPECT_FALSE(referenceIntersects(kFloor, apart));
}

TEST(TrianglePair, TouchingAtASharedVertexIsOneHitEachWay) {
  // The other triangle leans away from the floor, sharing only the origin. Whichever corner the
  // origin is in each triangle, each direction reports it once: both edges at that corner reach
  // the other plane there, and the second is the first's point exactly.
  const TriangleCorners leaning = {Vec3(0, 0, 0), Vec3(-4, 0, 4), Vec3(0, -4, 4)};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      TrianglePairHits hits;
      ASSERT_TRUE(intersectTrianglePair(rotated(kFloor, i), rotated(leaning, j), hits));
      ASSERT_EQ(hits.firstCount, 1) << i << j;
      ASSERT_EQ(hits.secondCount, 1) << i << j;
      EXPECT_EQ(hits.firstEdges[0].hit.point, Vec3::Zero());
      EXPECT_EQ(hits.secondEdges[0].hit.point, Vec3::Zero());
    }
  EXPECT_TRUE(referenceIntersects(kFloor, leaning));
}

TEST(TrianglePair, CornerOnTheFaceIsOneHitWhicheverCornerItIs) {
  // A corner in the floor's interior, the others above it: edges k−1 and k both end there. The
  // first in pass order reports it: edge 0 for corner 0 (0 before 2), edge k − 1 otherwise.
  const TriangleCorners standing = {Vec3(2, 2, 0), Vec3(1, 2, 4), Vec3(3, 2, 4)};
  for (int k = 0; k < 3; ++k) {
    const TriangleCorners t = rotated(standing, (3 - k) % 3);  // the floor corner at index k
    ASSERT_EQ(t[k], Vec3(2, 2, 0));
    std::array<EdgeHit, 2> hits;
    ASSERT_EQ(intersectEdgesWithTriangle(t, kFloor, hits), 1) << "corner " << k;
    EXPECT_EQ(hits[0].edge, k == 0 ? 0 : k - 1);
    EXPECT_EQ(hits[0].hit.point, Vec3(2, 2, 0));
  }
  // Where start + 1·(end − start) rounds (1.7f + (0.3f − 1.7f) ≠ 0.3f), the corner still comes
  // back once, and exactly.
  const TriangleCorners rounding = {Vec3(1.7f, 1.7f, 0.5f), Vec3(0.3f, 0.7f, 0),
                                    Vec3(2.9f, 0.3f, 0.5f)};
  std::array<EdgeHit, 2> hits;
  ASSERT_EQ(intersectEdgesWithTriangle(rounding, kFloor, hits), 1);
  EXPECT_EQ(hits[0].edge, 0);
  EXPECT_EQ(hits[0].hit.point, rounding[1]);
}

TEST(TrianglePair, EdgeThroughAFaceVertexIsOneHitEachWay) {
  // Edge 0 of `spike` runs up the z axis through the floor's corner at the origin; the floor's
  // edges 0 and 2 meet the spike's plane x = y at that corner, which lies on the spike's edge 0.
  const TriangleCorners spike = {Vec3(0, 0, -1), Vec3(0, 0, 1), Vec3(-4, -4, 3)};
  TrianglePairHits hits;
  ASSERT_TRUE(intersectTrianglePair(spike, kFloor, hits));
  ASSERT_EQ(hits.firstCount, 1);
  EXPECT_EQ(hits.firstEdges[0].edge, 0);
  EXPECT_EQ(hits.firstEdges[0].hit.point, Vec3::Zero());
  EXPECT_EQ(hits.firstEdges[0].hit.barycentric, Vec3(1, 0, 0));
  ASSERT_EQ(hits.secondCount, 1);
  EXPECT_EQ(hits.secondEdges[0].edge, 0);
  EXPECT_EQ(hits.secondEdges[0].hit.point, Vec3::Zero());
}

TEST(TrianglePair, SharedEdgeGivesItsTwoEndsEachWay) {
  // Folded down along the floor's edge 0: that edge is in both planes and crosses neither; the
  // other edges reach the other plane at the shared edge's ends.
  const TriangleCorners folded = {Vec3(0, 0, 0), Vec3(8, 0, 0), Vec3(4, 0, -4)};
  TrianglePairHits hits;
  ASSERT_TRUE(intersectTrianglePair(kFloor, folded, hits));
  ASSERT_EQ(hits.firstCount, 2);
  ASSERT_EQ(hits.secondCount, 2);
  EXPECT_EQ(hits.firstEdges[0].hit.point, Vec3(8, 0, 0));
  EXPECT_EQ(hits.firstEdges[1].hit.point, Vec3(0, 0, 0));
  EXPECT_EQ(hits.secondEdges[0].hit.point, Vec3(8, 0, 0));
  EXPECT_EQ(hits.secondEdges[1].hit.point, Vec3(0, 0, 0));
}

TEST(TrianglePair, CollapsedTriangleIsASegmentHitOnce) {
  // Collinear corners (the float cross product is exactly zero): the longest edge covers the
  // other two, so a crossing is one hit. The corners were picked so that the two edges crossing
  // the floor round their crossings differently (y = 1.30000007 vs 1.29999995 for a, b, c;
  // y = 0.942708373 vs 0.942708313 for p, p, q): without the rule they would be two hits.
  const Vec3 a(3.3125f, 2.5f, -0.75f), b(2.9609375f, 1.25f, 0.03125f),
      c(2.92578125f, 1.125f, 0.109375f);
  const Vec3 p(2.9375f, 1.4375f, -0.625f), q(1.8125f, 0.76953125f, 0.21875f);
  const std::array<TriangleCorners, 3> collapsed = {{
      {a, b, c},  // b between a and c: edge 2 (c → a) is the longest
      {b, c, a},  // the same, rotated: edge 1
      {p, p, q},  // two coincident corners: edges 1 and 2 are one segment both ways
  }};
  const std::array<int, 3> longest = {2, 1, 1};
  for (int i = 0; i < 3; ++i) {
    const TriangleCorners& t = collapsed[i];
    ASSERT_EQ((t[1] - t[0]).cross(t[2] - t[0]), Vec3::Zero());
    TrianglePairHits hits;
    ASSERT_TRUE(intersectTrianglePair(t, kFloor, hits)) << i;
    ASSERT_EQ(hits.firstCount, 1) << i;
    EXPECT_EQ(hits.firstEdges[0].edge, longest[i]);
    EXPECT_NEAR(hits.firstEdges[0].hit.point.z(), 0, 1e-6);
    EXPECT_EQ(hits.secondCount, 0) << "a collapsed face has no plane";
    EXPECT_TRUE(referenceIntersects(t, kFloor));
  }
}

TEST(TrianglePair, DegeneratePairsGiveNoHitAndNoNaN) {
  const TriangleCorners point = {Vec3(1, 1, 0), Vec3(1, 1, 0), Vec3(1, 1, 0)};  // on the floor
  const TriangleCorners segment = {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, 1, 0)};
  const TriangleCorners flat = {Vec3(0, 1, 0), Vec3(4, 1, 0), Vec3(2, 1, 0)};
  const std::array<std::array<TriangleCorners, 2>, 4> pairs = {
      {{kFloor, point}, {point, point}, {segment, flat}, {segment, point}}};
  for (const auto& pair : pairs) {
    TrianglePairHits hits;
    hits.firstEdges[0].hit.t = 7;
    EXPECT_FALSE(intersectTrianglePair(pair[0], pair[1], hits));
    EXPECT_EQ(hits.firstCount + hits.secondCount, 0);
    EXPECT_EQ(hits.firstEdges[0].hit.t, Scalar(7));
  }
}

TEST(TrianglePairReference, CoplanarAndCollapsedCasesFollowTheClosedSets) {
  auto intersects = [](const TriangleCorners& a, const TriangleCorners& b) {
    return referenceIntersects(a, b) && referenceIntersects(b, a);
  };
  // Coplanar: containment without crossing edges, touching at a vertex or along an edge.
  EXPECT_TRUE(intersects(kFloor, {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)}));
  EXPECT_TRUE(intersects(kFloor, {Vec3(8, 0, 0), Vec3(9, 0, 0), Vec3(9, 1, 0)}));
  EXPECT_TRUE(intersects(kFloor, {Vec3(4, 4, 0), Vec3(8, 8, 0), Vec3(0, 8, 0)}));
  EXPECT_FALSE(intersects(kFloor, {Vec3(5, 5, 0), Vec3(9, 5, 0), Vec3(5, 9, 0)}));
  // Non-coplanar touching: a corner on the face, an edge across an edge.
  EXPECT_TRUE(intersects(kFloor, {Vec3(2, 2, 0), Vec3(1, 2, 4), Vec3(3, 2, 4)}));
  EXPECT_TRUE(intersects(kFloor, {Vec3(4, -1, 0), Vec3(4, 1, 0), Vec3(4, 0, 3)}));
  EXPECT_FALSE(intersects(kFloor, {Vec3(2, 2, 1), Vec3(1, 2, 4), Vec3(3, 2, 4)}));
  // A collapsed triangle is its segment: in the plane across the face, in the plane on the line
  // through an edge but beyond it, and piercing.
  EXPECT_TRUE(intersects(kFloor, {Vec3(-1, 1, 0), Vec3(9, 1, 0), Vec3(3, 1, 0)}));
  EXPECT_FALSE(intersects(kFloor, {Vec3(9, 0, 0), Vec3(12, 0, 0), Vec3(10, 0, 0)}));
  EXPECT_TRUE(intersects(kFloor, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, 1, 1)}));
  EXPECT_FALSE(intersects(kFloor, {Vec3(1, 1, 1), Vec3(1, 1, 2), Vec3(1, 1, 3)}));
}

// ---------------------------------------------------------------------------------------------
// Random pairs against the double reference. The band is the line–triangle test's (4ε; see
// line_triangle_test.cpp), applied to each of the six edge–face tests:
// test::classifyTrianglePair calls a pair ambiguous when Möller finds an intersection but no edge
// crosses the other face clear of its band, or finds none but some edge comes within its band of
// the other face.

constexpr double kPairBandEpsilon = 4 * double(std::numeric_limits<Scalar>::epsilon());

enum PairKind { kOrdinaryPair, kSliverPair, kNearlyParallel, kPairKinds };
constexpr const char* kPairKindNames[kPairKinds] = {"ordinary", "sliver", "nearly parallel"};

struct RandomPair {
  TriangleCorners first, second;
  PairKind kind;
};

/// Triangles of log-uniform size 10^-3…10^3 anywhere within 20 sizes of the origin, the second
/// offset by up to 0.2 sizes per axis, so that about a third intersect. In one pair in ten
/// the second is a sliver 10^-3…10^-1 sizes wide, two sizes long, through a point of the first
/// (grown by 30% about its centroid); in one in ten it is the first moved in its plane and
/// tilted by 10^-3…10^-1 rad.
RandomPair randomPair(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1, 1), zeroOne(0, 1);
  auto vec = [&] { return Vec3d(unit(rng), unit(rng), unit(rng)); };
  const double size = std::pow(10.0, 6 * zeroOne(rng) - 3);
  const Vec3d center = 20 * size * vec(), offset = 0.2 * size * vec();
  test::TriangleD first, second;
  for (int k = 0; k < 3; ++k) {
    first[k] = center + size * vec();
    second[k] = center + offset + size * vec();
  }
  const double draw = zeroOne(rng);
  const PairKind kind = draw < 0.1 ? kSliverPair : draw > 0.9 ? kNearlyParallel : kOrdinaryPair;
  const Vec3d n = (first[1] - first[0]).cross(first[2] - first[0]).normalized();
  if (kind == kSliverPair) {
    double u = zeroOne(rng), v = zeroOne(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3d centroid = (first[0] + first[1] + first[2]) / 3;
    const Vec3d through = centroid + 1.3 * (first[0] + u * (first[1] - first[0]) +
                                            v * (first[2] - first[0]) - centroid);
    const Vec3d axis = size * vec().normalized();
    second[0] = through - axis;
    second[1] = through + axis;
    second[2] = through + unit(rng) * axis + std::pow(10.0, 2 * zeroOne(rng) - 3) * size * vec();
  }
  if (kind == kNearlyParallel) {
    auto inPlane = [&](const Vec3d& v) { return Vec3d(v - v.dot(n) * n); };
    const Vec3d shift = inPlane(0.5 * size * vec());
    const double tilt = std::pow(10.0, 2 * zeroOne(rng) - 3);
    for (int k = 0; k < 3; ++k)
      second[k] = first[k] + shift + inPlane(0.3 * size * vec()) + tilt * size * unit(rng) * n;
  }
  RandomPair pair;
  for (int k = 0; k < 3; ++k) {
    pair.first[k] = first[k].cast<Scalar>();
    pair.second[k] = second[k].cast<Scalar>();
  }
  pair.kind = kind;
  return pair;
}

/// Every hit of one direction lies on its edge and on the face, within the band's tolerance for
/// that edge–face test; hits come in edge order and no point twice.
void expectHitsOnBothTriangles(const TriangleCorners& edges, const TriangleCorners& face,
                               const std::array<EdgeHit, 2>& hits, int count, int pairIndex) {
  ASSERT_GE(count, 0);
  ASSERT_LE(count, 2);
  if (count == 2) {
    EXPECT_LT(hits[0].edge, hits[1].edge) << "pair " << pairIndex;
    EXPECT_NE(hits[0].hit.point, hits[1].hit.point) << "pair " << pairIndex;
  }
  const test::TriangleD e = test::toDouble(edges), f = test::toDouble(face);
  for (int i = 0; i < count; ++i) {
    const int edge = hits[i].edge;
    ASSERT_LT(edge, 3);
    const Vec3d point = hits[i].hit.point.cast<double>();
    ASSERT_TRUE(point.allFinite()) << "pair " << pairIndex;
    const Vec3d &start = e[edge], &end = e[(edge + 1) % 3];
    const double tolerance =
        test::segmentTriangleBand(start, end, f[0], f[1], f[2], kPairBandEpsilon).pointTolerance;
    EXPECT_LE(test::pointSegmentDistance(point, start, end), tolerance) << "pair " << pairIndex;
    EXPECT_LE(test::pointTriangleDistance(point, f[0], f[1], f[2]), tolerance)
        << "pair " << pairIndex;
  }
}

TEST(TrianglePairRandom, AgreesWithMollersTriangleTestOutsideTheRoundingBand) {
  std::mt19937 rng(20240612);
  constexpr int kPairs = 100000;
  int count[kPairKinds] = {}, intersecting[kPairKinds] = {}, ambiguous[kPairKinds] = {},
      disagreements[kPairKinds] = {};
  for (int i = 0; i < kPairs; ++i) {
    const RandomPair pair = randomPair(rng);
    const TriangleCorners &first = pair.first, &second = pair.second;
    const test::TriangleD firstD = test::toDouble(first), secondD = test::toDouble(second);
    TrianglePairHits hits;
    const bool code = intersectTrianglePair(first, second, hits);
    const bool reference = test::trianglesIntersect(firstD, secondD);
    const test::PairVerdict verdict = test::classifyTrianglePair(firstD, secondD, kPairBandEpsilon);
    ASSERT_NE(verdict, test::PairVerdict::Inconsistent)
        << "pair " << i << ": the two double references disagree";
    ++count[pair.kind];
    intersecting[pair.kind] += reference;
    ambiguous[pair.kind] += verdict == test::PairVerdict::Ambiguous;
    if (code != reference) {
      ++disagreements[pair.kind];
      ASSERT_EQ(verdict, test::PairVerdict::Ambiguous)
          << "pair " << i << ": code " << code << ", reference " << reference
          << ", outside the rounding band";
    }

    expectHitsOnBothTriangles(first, second, hits.firstEdges, hits.firstCount, i);
    expectHitsOnBothTriangles(second, first, hits.secondEdges, hits.secondCount, i);
    // The directions are independent: swapping the arguments swaps the results bit for bit.
    TrianglePairHits swapped;
    intersectTrianglePair(second, first, swapped);
    ASSERT_EQ(swapped.firstCount, hits.secondCount);
    ASSERT_EQ(swapped.secondCount, hits.firstCount);
    for (int k = 0; k < hits.firstCount; ++k)
      EXPECT_EQ(swapped.secondEdges[k].hit.point, hits.firstEdges[k].hit.point);
  }
  int total = 0;
  for (int kind = 0; kind < kPairKinds; ++kind) {
    EXPECT_GT(intersecting[kind], count[kind] / 5) << kPairKindNames[kind];
    EXPECT_LT(intersecting[kind], count[kind] * 4 / 5) << kPairKindNames[kind];
    total += disagreements[kind];
    std::cout << "[          ] " << kPairKindNames[kind] << ": " << count[kind] << " pairs, "
              << intersecting[kind] << " intersecting, " << ambiguous[kind] << " in the band, "
              << disagreements[kind] << " disagreements\n";
  }
  EXPECT_LT(ambiguous[kOrdinaryPair], count[kOrdinaryPair] / 200);
  EXPECT_LT(ambiguous[kSliverPair] + ambiguous[kNearlyParallel],
            (count[kSliverPair] + count[kNearlyParallel]) / 2);
  EXPECT_LE(total, kPairs / 1000);
}

}  // namespace
}  // namespace softbake
