// The continuous vertex–face and edge–edge tests (core/collision/continuous_collision) against
// analytic cases and a brute-force reference: the primitives' distance sampled densely over the
// substep, in double precision, by code that shares nothing with the cubic and its roots.
#include "core/collision/continuous_collision.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <functional>
#include <random>

#include "tests/support/exact_geometry.hpp"

namespace softbake {
namespace {

using test::pointTriangleDistance;

constexpr double kTolerance = 1e-6;

PointPath still(double x, double y, double z) {
  return {Vec3d(x, y, z), Vec3d(x, y, z)};
}
PointPath moving(const Vec3d& from, const Vec3d& to) {
  return {from, to};
}

double pointSegmentDistance(const Vec3d& p, const Vec3d& x, const Vec3d& y) {
  const double s = std::clamp((p - x).dot(y - x) / (y - x).squaredNorm(), 0.0, 1.0);
  return (p - (x + s * (y - x))).norm();
}

double segmentDistance(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0, const Vec3d& q1) {
  // The distance is a convex quadratic in (s, u): its minimum over the unit square is the
  // stationary point when that lies inside, or else lies on the square's boundary, where one
  // parameter is 0 or 1 and the distance is a point's to the other segment.
  double best = std::min({pointSegmentDistance(p0, q0, q1), pointSegmentDistance(p1, q0, q1),
                          pointSegmentDistance(q0, p0, p1), pointSegmentDistance(q1, p0, p1)});
  const Vec3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  Eigen::Matrix2d m;
  m << d1.dot(d1), -d1.dot(d2), -d1.dot(d2), d2.dot(d2);
  if (std::abs(m.determinant()) > 1e-12) {
    const Eigen::Vector2d su = m.inverse() * Eigen::Vector2d(-d1.dot(r), d2.dot(r));
    if (su.minCoeff() >= 0 && su.maxCoeff() <= 1)
      best = std::min(best, ((p0 + su[0] * d1) - (q0 + su[1] * d2)).norm());
  }
  return best;
}

TEST(VertexFaceImpact, AVertexThroughTheMiddleOfAStillFaceMeetsItHalfWay) {
  const auto impact = vertexFaceImpact(moving({0.2, 0.2, 1}, {0.2, 0.2, -1}), still(0, 0, 0),
                                       still(1, 0, 0), still(0, 1, 0), kTolerance);
  ASSERT_TRUE(impact);
  EXPECT_NEAR(impact->t, 0.5, 1e-9);
  EXPECT_NEAR(impact->weight[0], 1, 1e-12);
  EXPECT_NEAR(impact->weight[1], -0.6, 1e-9);
  EXPECT_NEAR(impact->weight[2], -0.2, 1e-9);
  EXPECT_NEAR(impact->weight[3], -0.2, 1e-9);
  // From the face towards where the vertex came from.
  EXPECT_NEAR(impact->normal.z(), 1, 1e-12);
}

TEST(VertexFaceImpact, AFaceMovingOntoAStillVertexMeetsItWhenItArrives) {
  // The face rises from z = −1 to z = 3 under a vertex at z = 0.5: it arrives at t = 3/8.
  const auto up = [](double x, double y) { return moving({x, y, -1}, {x, y, 3}); };
  const auto impact =
      vertexFaceImpact(still(0.25, 0.25, 0.5), up(0, 0), up(1, 0), up(0, 1), kTolerance);
  ASSERT_TRUE(impact);
  EXPECT_NEAR(impact->t, 0.375, 1e-9);
  EXPECT_NEAR(impact->normal.z(), 1, 1e-12);
}

TEST(VertexFaceImpact, AVertexPassingBesideTheFaceDoesNotMeetIt) {
  EXPECT_FALSE(vertexFaceImpact(moving({1.2, 1.2, 1}, {1.2, 1.2, -1}), still(0, 0, 0),
                                still(1, 0, 0), still(0, 1, 0), kTolerance));
}

TEST(VertexFaceImpact, ARotatingFaceSweepsThroughAVertexItsPlaneNeverHeldAtEitherEnd) {
  // The face turns about the x axis from below the vertex (z = −0.5 at its far corner) to above it
  // (z = +0.5): the vertex at (0.2, 0.5, 0.05) lies on neither end's plane, only in between.
  const PointPath a = still(0, 0, 0), b = still(1, 0, 0);
  const PointPath c = moving({0, 0.866, -0.5}, {0, 0.866, 0.5});
  const auto impact = vertexFaceImpact(still(0.2, 0.5, 0.05), a, b, c, kTolerance);
  ASSERT_TRUE(impact);
  EXPECT_GT(impact->t, 0.5);
  EXPECT_LT(impact->t, 0.6);
}

TEST(EdgeEdgeImpact, TwoCrossingEdgesMeetWhenTheirLinesDo) {
  // Edge p along x at z = 1 − 2t, edge q along y at z = 0: they meet at t = 1/2, at s = u = 1/2.
  const auto impact = edgeEdgeImpact(moving({-1, 0, 1}, {-1, 0, -1}), moving({1, 0, 1}, {1, 0, -1}),
                                     still(0, -1, 0), still(0, 1, 0), kTolerance);
  ASSERT_TRUE(impact);
  EXPECT_NEAR(impact->t, 0.5, 1e-9);
  EXPECT_NEAR(impact->weight[0], 0.5, 1e-9);
  EXPECT_NEAR(impact->weight[1], 0.5, 1e-9);
  EXPECT_NEAR(impact->weight[2], -0.5, 1e-9);
  EXPECT_NEAR(impact->weight[3], -0.5, 1e-9);
  EXPECT_NEAR(impact->normal.z(), 1, 1e-12);
}

TEST(EdgeEdgeImpact, EdgesWhoseLinesMeetBeyondTheirEndsDoNotMeet) {
  EXPECT_FALSE(edgeEdgeImpact(moving({-1, 2, 1}, {-1, 2, -1}), moving({1, 2, 1}, {1, 2, -1}),
                              still(0, -1, 0), still(0, 1, 0), kTolerance));
}

class RandomMotions : public ::testing::Test {
 protected:
  std::mt19937 random_{12345};
  std::uniform_real_distribution<double> unit_{-1, 1};
  Vec3d point() { return {unit_(random_), unit_(random_), unit_(random_)}; }
  PointPath path() { return {point(), point()}; }
};

constexpr int kSamples = 2000;

/// Against the sampled reference distance `distance(t)`: an aimed pair (known to meet at `aimedAt`)
/// is found no later than that; a reported meeting is one (the reference distance there is within
/// the tolerance); and no earlier meeting went unreported.
template <typename Distance>
void checkAgainstSamples(const std::optional<Impact>& impact, double aimedAt, Distance distance,
                         int trial, int& meetings) {
  if (aimedAt >= 0) {
    ASSERT_TRUE(impact) << "trial " << trial << " meets at " << aimedAt;
    EXPECT_LE(impact->t, aimedAt + 1e-9) << trial;
  }
  if (!impact) return;
  ++meetings;
  EXPECT_LE(distance(impact->t), 1.0001 * kTolerance) << trial;
  // A meeting is reported at the instant the two are coplanar; closing slowly, they may be within
  // the tolerance a little before. That is the same meeting when they stay within it from then on;
  // one that came and went earlier would be a missed meeting.
  int firstClose = -1;
  for (int i = 0; i <= kSamples && double(i) / kSamples < impact->t; ++i) {
    const double d = distance(double(i) / kSamples);
    if (firstClose < 0 && d <= 0.5 * kTolerance) firstClose = i;
    if (firstClose >= 0) {
      ASSERT_LE(d, 1.01 * kTolerance) << trial << ": apart again at " << i;
    }
  }
}

TEST_F(RandomMotions, VertexFaceMeetingsAgreeWithASampledDistance) {
  int meetings = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const PointPath a = path(), b = path(), c = path();
    PointPath p = path();
    double aimedAt = -1;
    // Half the trials aim the vertex at the face: through a random point of it at a random time.
    if (trial % 2 == 0) {
      aimedAt = std::uniform_real_distribution<double>(0, 1)(random_);
      double u = std::uniform_real_distribution<double>(0, 1)(random_);
      double v = std::uniform_real_distribution<double>(0, 1)(random_);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      const Vec3d target = (1 - u - v) * a.at(aimedAt) + u * b.at(aimedAt) + v * c.at(aimedAt);
      const Vec3d velocity = point();
      p = {target - aimedAt * velocity, target + (1 - aimedAt) * velocity};
    }
    checkAgainstSamples(
        vertexFaceImpact(p, a, b, c, kTolerance), aimedAt,
        [&](double t) { return pointTriangleDistance(p.at(t), a.at(t), b.at(t), c.at(t)); }, trial,
        meetings);
  }
  EXPECT_GE(meetings, 1000);  // every aimed vertex, and some of the rest
}

TEST_F(RandomMotions, EdgeEdgeMeetingsAgreeWithASampledDistance) {
  int meetings = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    PointPath p0 = path(), p1 = path();
    const PointPath q0 = path(), q1 = path();
    double aimedAt = -1;
    if (trial % 2 == 0) {
      // Aim: shift the first edge so that a point of it passes through a point of the other.
      aimedAt = std::uniform_real_distribution<double>(0, 1)(random_);
      const double s = std::uniform_real_distribution<double>(0, 1)(random_);
      const double u = std::uniform_real_distribution<double>(0, 1)(random_);
      const Vec3d shift = (q0.at(aimedAt) + u * (q1.at(aimedAt) - q0.at(aimedAt))) -
                          (p0.at(aimedAt) + s * (p1.at(aimedAt) - p0.at(aimedAt)));
      p0 = {p0.start + shift, p0.end + shift};
      p1 = {p1.start + shift, p1.end + shift};
    }
    checkAgainstSamples(
        edgeEdgeImpact(p0, p1, q0, q1, kTolerance), aimedAt,
        [&](double t) { return segmentDistance(p0.at(t), p1.at(t), q0.at(t), q1.at(t)); }, trial,
        meetings);
  }
  EXPECT_GE(meetings, 1000);
}

/// Primitives carried along together by one large motion, each point with a small motion of its
/// own, and started within a few times (tolerance + that motion) of each other: the pairs the
/// distance bound may reject before the cubic. Every pair the sampled distance brings within half
/// the tolerance must be found, and every pair found must be one.
TEST_F(RandomMotions, PrimitivesMovingTogetherMeetExactlyWhenTheirSampledDistanceSaysSo) {
  constexpr double kJitter = 1e-5;
  std::uniform_real_distribution<double> reach(0, 2 * (kTolerance + 2 * kJitter));
  const auto carried = [&](const Vec3d& start, const Vec3d& common) {
    return PointPath{start, start + common + kJitter * point() / std::sqrt(3.0)};
  };
  int found = 0, close = 0, rejected = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const Vec3d common = point();
    const Vec3d a0 = point(), b0 = point(), c0 = point();
    const Vec3d normal = (b0 - a0).cross(c0 - a0).normalized();
    if (!normal.allFinite()) continue;
    std::optional<Impact> impact;
    std::function<double(double)> distance;
    PointPath a = carried(a0, common), b = carried(b0, common), c = carried(c0, common);
    if (trial % 2 == 0) {
      const PointPath p = carried((a0 + b0 + c0) / 3 + reach(random_) * normal, common);
      impact = vertexFaceImpact(p, a, b, c, kTolerance);
      distance = [=](double t) {
        return pointTriangleDistance(p.at(t), a.at(t), b.at(t), c.at(t));
      };
    } else {
      // An edge across the triangle's middle, lifted off it: the two edges' closest points are
      // inside both.
      const Vec3d lift = reach(random_) * normal, middle = (a0 + b0 + c0) / 3;
      const Vec3d along = normal.cross(b0 - a0).normalized() * 0.1;
      const PointPath q0 = carried(middle + lift - along, common);
      const PointPath q1 = carried(middle + lift + along, common);
      const PointPath m0 = carried(middle - 0.1 * (b0 - a0), common);
      const PointPath m1 = carried(middle + 0.1 * (b0 - a0), common);
      impact = edgeEdgeImpact(q0, q1, m0, m1, kTolerance);
      distance = [=](double t) { return segmentDistance(q0.at(t), q1.at(t), m0.at(t), m1.at(t)); };
    }
    double closest = HUGE_VAL;
    for (int i = 0; i <= kSamples; ++i) closest = std::min(closest, distance(double(i) / kSamples));
    if (closest <= 0.5 * kTolerance) {
      ++close;
      EXPECT_TRUE(impact) << "trial " << trial << " comes within " << closest;
    }
    if (impact) {
      ++found;
      EXPECT_LE(distance(impact->t), 1.0001 * kTolerance) << trial;
    } else if (distance(0) > kTolerance) {
      ++rejected;
    }
  }
  // Both sides of the bound are exercised: meetings found, and pairs apart at the start that
  // never met.
  EXPECT_GE(close, 150);
  EXPECT_GE(found, close);
  EXPECT_GE(rejected, 1000);
}

TEST(ClosestPointBarycentric, MatchesTheBruteForceDistance) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  const auto point = [&] { return Vec3d(unit(random), unit(random), unit(random)); };
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3d p = point(), a = point(), b = point(), c = point();
    const Vec3d w = closestPointBarycentric(p, a, b, c);
    EXPECT_NEAR(w.sum(), 1, 1e-12);
    EXPECT_GE(w.minCoeff(), -1e-12);
    EXPECT_NEAR((p - (w[0] * a + w[1] * b + w[2] * c)).norm(), pointTriangleDistance(p, a, b, c),
                1e-9);
  }
}

}  // namespace
}  // namespace softbake
