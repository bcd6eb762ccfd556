// intersectSegmentTriangle: exact analytic cases on power-of-two coordinates (every operation is
// exact in float, so results are compared with ==), then random segments against Möller–Trumbore
// in double.
#include "core/collision/line_triangle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>

#include "tests/support/exact_geometry.hpp"

namespace softbake {
namespace {

// The right triangle with legs 4 on x and y, in the plane z = 0.
const Vec3 kA(0, 0, 0), kB(4, 0, 0), kC(0, 4, 0);

bool hits(const Vec3& start, const Vec3& end, const Vec3& a = kA, const Vec3& b = kB,
          const Vec3& c = kC) {
  SegmentTriangleHit hit;
  return intersectSegmentTriangle(start, end, a, b, c, hit);
}

TEST(LineTriangle, InteriorCrossingGivesExactParameterPointAndWeights) {
  SegmentTriangleHit hit;
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(1, 1, -1), Vec3(1, 1, 3), kA, kB, kC, hit));
  // Plane distances −1 and 3 (times |n| = 16): t = 1/4, point (1, 1, 0) = ½a + ¼b + ¼c.
  EXPECT_EQ(hit.t, Scalar(0.25));
  EXPECT_EQ(hit.point, Vec3(1, 1, 0));
  EXPECT_EQ(hit.barycentric, Vec3(0.5, 0.25, 0.25));
}

TEST(LineTriangle, CrossingOnAnEdgeHitsWithAZeroWeight) {
  SegmentTriangleHit hit;
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(2, 0, -1), Vec3(2, 0, 1), kA, kB, kC, hit));
  EXPECT_EQ(hit.point, Vec3(2, 0, 0));
  EXPECT_EQ(hit.barycentric, Vec3(0.5, 0.5, 0));
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(2, 2, 1), Vec3(2, 2, -1), kA, kB, kC, hit));
  EXPECT_EQ(hit.barycentric, Vec3(0, 0.5, 0.5));  // the hypotenuse
  // 2^-20 beyond an edge is outside: the closed triangle is no wider than it is.
  EXPECT_FALSE(hits(Vec3(2, -std::ldexp(1.0f, -20), -1), Vec3(2, -std::ldexp(1.0f, -20), 1)));
  EXPECT_FALSE(hits(Vec3(2 + std::ldexp(1.0f, -20), 2, -1), Vec3(2 + std::ldexp(1.0f, -20), 2, 1)));
}

TEST(LineTriangle, CrossingThroughAVertexHitsThatVertex) {
  SegmentTriangleHit hit;
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(4, 0, 2), Vec3(4, 0, -2), kA, kB, kC, hit));
  EXPECT_EQ(hit.t, Scalar(0.5));
  EXPECT_EQ(hit.point, kB);
  EXPECT_EQ(hit.barycentric, Vec3(0, 1, 0));
  // Slanted through a: the point is still exactly the vertex.
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(-1, -2, -1), Vec3(1, 2, 1), kA, kB, kC, hit));
  EXPECT_EQ(hit.point, kA);
  EXPECT_EQ(hit.barycentric, Vec3(1, 0, 0));
}

TEST(LineTriangle, SegmentInThePlaneDoesNotHitEvenAcrossTheTriangle) {
  EXPECT_FALSE(hits(Vec3(-1, 1, 0), Vec3(5, 1, 0)));
  EXPECT_FALSE(hits(Vec3(1, 1, 0), Vec3(2, 1, 0)));  // wholly inside
}

TEST(LineTriangle, ParallelSegmentOffThePlaneDoesNotHit) {
  EXPECT_FALSE(hits(Vec3(-1, 1, 1), Vec3(5, 1, 1)));
  EXPECT_FALSE(hits(Vec3(1, 1, -0.5f), Vec3(2, 1, -0.5f)));
}

TEST(LineTriangle, EndpointExactlyOnThePlaneHitsAtThatEndpoint) {
  SegmentTriangleHit hit;
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(1, 1, 0), Vec3(3, 5, 7), kA, kB, kC, hit));
  EXPECT_EQ(hit.t, Scalar(0));
  EXPECT_EQ(hit.point, Vec3(1, 1, 0));
  // The end on the plane comes back bit for bit: here 1.7f + (0.3f − 1.7f) rounds to 0.29999995
  // and 1.7f + (0.7f − 1.7f) to 0.70000005.
  const Vec3 start(1.7f, 1.7f, 0.5f), end(0.3f, 0.7f, 0);
  ASSERT_TRUE(intersectSegmentTriangle(start, end, kA, kB, kC, hit));
  EXPECT_EQ(hit.t, Scalar(1));
  EXPECT_EQ(hit.point, end);
  // On the plane but outside the triangle: no hit.
  EXPECT_FALSE(hits(Vec3(5, 5, 0), Vec3(5, 5, 1)));
}

TEST(LineTriangle, DegenerateTrianglesNeverHitAndWriteNothing) {
  const std::array<std::array<Vec3, 3>, 4> degenerate = {{
      {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2)},  // collinear, crossed by the segment's line
      {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(2, 0, 0)},  // collinear, corner between the others
      {Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 4, 0)},  // two coincident corners
      {Vec3(1, 1, 0), Vec3(1, 1, 0), Vec3(1, 1, 0)},  // all coincident
  }};
  const std::array<std::array<Vec3, 2>, 3> segments = {{
      {Vec3(1, 1, -1), Vec3(1, 1, 1)},
      {Vec3(1, 1, 1), Vec3(1, 1, 1)},  // zero length, on the first triangle
      {Vec3(2, -1, 0), Vec3(2, 1, 0)},
  }};
  for (const auto& t : degenerate)
    for (const auto& s : segments) {
      SegmentTriangleHit hit;
      hit.t = 7;
      EXPECT_FALSE(intersectSegmentTriangle(s[0], s[1], t[0], t[1], t[2], hit));
      EXPECT_EQ(hit.t, Scalar(7));
      EXPECT_TRUE(hit.point.allFinite() && hit.barycentric.allFinite());
    }
}

TEST(LineTriangle, BothWindingsGiveTheSameHit) {
  const Vec3 start(0.3f, 0.6f, -1.7f), end(1.1f, 0.2f, 2.3f);
  const Vec3 a(-0.5f, 0.1f, 0.2f), b(2.5f, -0.3f, 0.4f), c(0.2f, 2.2f, -0.1f);
  SegmentTriangleHit forward, backward;
  ASSERT_TRUE(intersectSegmentTriangle(start, end, a, b, c, forward));
  ASSERT_TRUE(intersectSegmentTriangle(start, end, a, c, b, backward));
  // The normal flips sign, and t = s0/(s0 − s1) with it: bit-identical t and point.
  EXPECT_EQ(forward.t, backward.t);
  EXPECT_EQ(forward.point, backward.point);
  // Each 2D area is the same products in the other order, negated with the total: exact too.
  EXPECT_EQ(forward.barycentric,
            Vec3(backward.barycentric[0], backward.barycentric[2], backward.barycentric[1]));
}

TEST(LineTriangle, ThinSliverIsHitInsideAndMissedJustOutside) {
  // Height 2^-20 over a base of 1: aspect ratio 10^6.
  const Scalar h = std::ldexp(Scalar(1), -20);
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0.5f, h, 0);
  SegmentTriangleHit hit;
  ASSERT_TRUE(intersectSegmentTriangle(Vec3(0.5f, h / 4, -1), Vec3(0.5f, h / 4, 1), a, b, c, hit));
  EXPECT_EQ(hit.point, Vec3(0.5f, h / 4, 0));
  EXPECT_EQ(hit.barycentric, Vec3(0.375, 0.375, 0.25));
  EXPECT_FALSE(hits(Vec3(0.5f, h * 1.25f, -1), Vec3(0.5f, h * 1.25f, 1), a, b, c));
  EXPECT_FALSE(hits(Vec3(0.5f, -h / 4, -1), Vec3(0.5f, -h / 4, 1), a, b, c));
}

// ---------------------------------------------------------------------------------------------
// Random inputs against the double reference.
//
// Rounding band: test::segmentTriangleBand with relativeEpsilon = 4·ε (ε = 2^-23 for float): a
// first-order bound on the float test's error, a few ulps of the inputs' extent R per rounded
// operation, magnified by the triangle's conditioning κ and, along the segment, by how obliquely
// it meets the plane (see exact_geometry.hpp). The bound is conservative: when the test was
// written the worst disagreement needed 0.03·ε (slivers) and 0.02·ε (grazing segments), so 4·ε
// is a margin of over 100. The share of ambiguous cases is bounded too, so a band that grows to
// swallow everything fails the test instead of hiding a bug.

constexpr double kBandEpsilon = 4 * double(std::numeric_limits<Scalar>::epsilon());

enum Kind { kOrdinary, kSliver, kGrazing, kKinds };
constexpr const char* kKindNames[kKinds] = {"ordinary", "sliver", "grazing"};

struct RandomCase {
  Vec3 start, end, a, b, c;
  Kind kind;
};

/// Triangles of log-uniform size 10^-3…10^3 anywhere within 20 sizes of the origin; segments of
/// 0.1…3 sizes through a point of the triangle grown by 30% about its centroid, so that about
/// 40% hit. One triangle in ten is a sliver (a corner 10^-3…10^-1 sizes off the opposite edge);
/// one segment in ten grazes the plane at 10^-3…10^-1 rad.
RandomCase randomCase(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1, 1), zeroOne(0, 1);
  auto vec = [&] { return Vec3d(unit(rng), unit(rng), unit(rng)); };
  const double size = std::pow(10.0, 6 * zeroOne(rng) - 3);
  const Vec3d center = 20 * size * vec();
  const Vec3d a = center + size * vec(), b = center + size * vec();
  Vec3d c = center + size * vec();
  const double draw = zeroOne(rng);
  const Kind kind = draw < 0.1 ? kSliver : draw > 0.9 ? kGrazing : kOrdinary;
  if (kind == kSliver)
    c = a + zeroOne(rng) * (b - a) + std::pow(10.0, 2 * zeroOne(rng) - 3) * size * vec();
  double u = zeroOne(rng), v = zeroOne(rng);
  if (u + v > 1) u = 1 - u, v = 1 - v;
  const Vec3d centroid = (a + b + c) / 3;
  const Vec3d target = centroid + 1.3 * (a + u * (b - a) + v * (c - a) - centroid);
  Vec3d direction = vec().normalized();
  if (kind == kGrazing) {
    const Vec3d n = (b - a).cross(c - a).normalized();
    const double angle = std::copysign(std::pow(10.0, 2 * zeroOne(rng) - 3), unit(rng));
    direction =
        std::cos(angle) * (direction - direction.dot(n) * n).normalized() + std::sin(angle) * n;
  }
  const double length = size * std::pow(10.0, 1.5 * zeroOne(rng) - 1);
  const Vec3d start = target - (1.4 * zeroOne(rng) - 0.2) * length * direction;
  const Vec3d end = start + length * direction;
  return {start.cast<Scalar>(), end.cast<Scalar>(), a.cast<Scalar>(),
          b.cast<Scalar>(),     c.cast<Scalar>(),   kind};
}

TEST(LineTriangleRandom, AgreesWithDoubleMollerTrumboreOutsideTheRoundingBand) {
  std::mt19937 rng(20240611);
  constexpr int kCases = 100000;
  int count[kKinds] = {}, hitsSeen[kKinds] = {}, ambiguous[kKinds] = {}, disagreements[kKinds] = {};
  double worstPointError = 0;  // as a fraction of the stated tolerance
  for (int i = 0; i < kCases; ++i) {
    const RandomCase k = randomCase(rng);
    const Vec3d s = k.start.cast<double>(), e = k.end.cast<double>(), a = k.a.cast<double>(),
                b = k.b.cast<double>(), c = k.c.cast<double>();
    SegmentTriangleHit hit;
    const bool code = intersectSegmentTriangle(k.start, k.end, k.a, k.b, k.c, hit);
    const test::ReferenceSegmentHit reference = test::mollerTrumbore(s, e, a, b, c);
    const test::SegmentTriangleBand band = test::segmentTriangleBand(s, e, a, b, c, kBandEpsilon);
    ++count[k.kind];
    hitsSeen[k.kind] += reference.hit;
    ambiguous[k.kind] += band.ambiguous;
    if (code != reference.hit) {
      ++disagreements[k.kind];
      ASSERT_TRUE(band.ambiguous) << "case " << i << ": code " << code << ", reference "
                                  << reference.hit << ", outside the rounding band";
    }
    if (!code) continue;
    ASSERT_TRUE(hit.point.allFinite() && hit.barycentric.allFinite()) << "case " << i;
    // The computed point lies on the segment and on the triangle, and its weights reproduce it.
    const Vec3d point = hit.point.cast<double>();
    const double tolerance = band.pointTolerance;
    EXPECT_LE(test::pointSegmentDistance(point, s, e), tolerance) << "case " << i;
    EXPECT_LE(test::pointTriangleDistance(point, a, b, c), tolerance) << "case " << i;
    // Relative to the point, so that the weights' rounding is not multiplied by the distance
    // from the origin.
    const Vec3d w = hit.barycentric.cast<double>();
    EXPECT_LE((w[0] * (a - point) + w[1] * (b - point) + w[2] * (c - point)).norm(), tolerance)
        << "case " << i;
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    EXPECT_LE(std::abs(w.sum() - 1), tolerance / longest) << "case " << i;
    if (reference.hit) {
      const double error = (point - reference.point).norm();
      EXPECT_LE(error, tolerance) << "case " << i;
      worstPointError = std::max(worstPointError, error / tolerance);
    }
  }
  int total = 0;
  for (int kind = 0; kind < kKinds; ++kind) {
    // Every kind exercises both outcomes.
    EXPECT_GT(hitsSeen[kind], count[kind] / 5) << kKindNames[kind];
    EXPECT_LT(hitsSeen[kind], count[kind] * 4 / 5) << kKindNames[kind];
    total += disagreements[kind];
    std::cout << "[          ] " << kKindNames[kind] << ": " << count[kind] << " cases, "
              << hitsSeen[kind] << " hits, " << ambiguous[kind] << " in the band, "
              << disagreements[kind] << " disagreements\n";
  }
  // Well-conditioned inputs are almost never near the band; the ill-conditioned kinds are there
  // to put some in it. Disagreements stay rare overall.
  EXPECT_LT(ambiguous[kOrdinary], count[kOrdinary] / 200);
  EXPECT_LT(ambiguous[kSliver] + ambiguous[kGrazing], (count[kSliver] + count[kGrazing]) / 2);
  EXPECT_LE(total, kCases / 1000);
  EXPECT_LE(worstPointError, 1);
  std::cout << "[          ] worst hit-point error " << worstPointError << " of the tolerance\n";
}

TEST(LineTriangleRandom, SegmentFromACornerHitsExactlyAtThatCorner) {
  // The corner's plane distance is exactly 0 and its weights exactly (1, 0, 0), whatever the
  // rounding elsewhere: a closed triangle contains its corners.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1, 1);
  auto vec = [&] { return Vec3(unit(rng), unit(rng), unit(rng)); };
  for (int i = 0; i < 10000; ++i) {
    const Vec3 a = vec(), b = vec(), c = vec(), away = a + vec();
    SegmentTriangleHit hit;
    ASSERT_TRUE(intersectSegmentTriangle(a, away, a, b, c, hit)) << "case " << i;
    EXPECT_EQ(hit.point, a);
    EXPECT_EQ(hit.barycentric, Vec3(1, 0, 0));
    ASSERT_TRUE(intersectSegmentTriangle(away, a, a, b, c, hit)) << "case " << i;
    EXPECT_EQ(hit.point, a);
  }
}

}  // namespace
}  // namespace softbake
