// The exact intersection checker (tests/support/intersection_checker) against an independent
// reference (Möller's interval test in double, tests/support/exact_geometry.hpp) wherever that
// reference is clear of rounding, and by hand where only exact arithmetic can tell; its
// penetration depth by hand and against a dense search over directions.
#include "tests/support/intersection_checker.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "tests/support/exact_geometry.hpp"

namespace softbake::test {
namespace {

/// Two triangles as two one-triangle surfaces (or one surface, with `sameSurface`).
CollisionGeometry twoTriangles(bool sameSurface = false) {
  CollisionGeometry geometry;
  geometry.surfaces.resize(sameSurface ? 1 : 2);
  geometry.triangleVertices = {{0, 1, 2}, {3, 4, 5}};
  geometry.triangleSurface = {0, Index(sameSurface ? 0 : 1)};
  geometry.particleCount = 6;
  geometry.softTriangleCount = 2;
  return geometry;
}

TEST(IntersectionChecker, AgreesWithTheDoubleReferenceOnRandomPairs) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-1, 1);
  const CollisionGeometry geometry = twoTriangles();
  std::size_t decided = 0, intersecting = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<Vec3> positions(6);
    for (Vec3& p : positions) p = Vec3(coordinate(random), coordinate(random), coordinate(random));
    const TriangleD first = toDouble({positions[0], positions[1], positions[2]});
    const TriangleD second = toDouble({positions[3], positions[4], positions[5]});
    const PairVerdict verdict = classifyTrianglePair(first, second, 1e-9);
    ASSERT_NE(verdict, PairVerdict::Inconsistent);
    if (verdict == PairVerdict::Ambiguous) continue;
    ++decided;
    const bool expected = verdict == PairVerdict::Intersecting;
    intersecting += expected;
    EXPECT_EQ(countIntersectingPairs(geometry, positions).betweenSurfaces, expected ? 1u : 0u)
        << "trial " << trial;
  }
  EXPECT_GT(decided, 19000u);
  EXPECT_GT(intersecting, 2000u) << "both answers must be exercised";
}

TEST(IntersectionChecker, TouchingCountsAndOneStepAwayDoesNot) {
  // A triangle's corner exactly on the other's interior touches it; moved off the plane by the
  // smallest float step it does not. Only exact predicates tell the two apart.
  const CollisionGeometry geometry = twoTriangles();
  std::vector<Vec3> positions = {Vec3(0, 0, 0),         Vec3(1, 0, 0),       Vec3(0, 1, 0),
                                 Vec3(0.25f, 0.25f, 0), Vec3(0.3f, 0.2f, 1), Vec3(0.2f, 0.3f, 1)};
  EXPECT_EQ(countIntersectingPairs(geometry, positions).betweenSurfaces, 1u);
  positions[3].z() = std::nextafter(0.0f, 1.0f);
  EXPECT_EQ(countIntersectingPairs(geometry, positions).betweenSurfaces, 0u);
  positions[3].z() = std::nextafter(0.0f, -1.0f);
  EXPECT_EQ(countIntersectingPairs(geometry, positions).betweenSurfaces, 1u);
}

TEST(IntersectionChecker, WithinASurfaceOnlyPairsThatShareNoVertexCount) {
  // Two triangles of one surface crossing each other: counted within the surface.
  CollisionGeometry geometry = twoTriangles(/*sameSurface=*/true);
  std::vector<Vec3> positions = {Vec3(0, 0, 0),        Vec3(1, 0, 0),       Vec3(0, 1, 0),
                                 Vec3(0.2f, 0.2f, -1), Vec3(0.3f, 0.2f, 1), Vec3(0.2f, 0.3f, 1)};
  IntersectionCount count = countIntersectingPairs(geometry, positions);
  EXPECT_EQ(count.withinSurfaces, 1u);
  EXPECT_EQ(count.betweenSurfaces, 0u);
  EXPECT_EQ((count.bySurfaces[{0, 0}]), 1u);
  // Neighbours sharing an edge touch along it by construction: not a self-intersection.
  geometry.triangleVertices[1] = {1, 2, 5};
  positions[5] = Vec3(1, 1, 0.1f);
  EXPECT_EQ(countIntersectingPairs(geometry, positions).withinSurfaces, 0u);
}

TEST(IntersectionChecker, ZeroAreaTrianglesAreSkipped) {
  const CollisionGeometry geometry = twoTriangles();
  const std::vector<Vec3> positions = {Vec3(0, 0, 0),       Vec3(1, 0, 0),
                                       Vec3(0, 1, 0),       Vec3(0.2f, 0.2f, -1),
                                       Vec3(0.2f, 0.2f, 1), Vec3(0.2f, 0.2f, 0)};
  EXPECT_EQ(countIntersectingPairs(geometry, positions).total(), 0u);
}

bool referenceIntersects(const TriangleCorners& first, const TriangleCorners& second) {
  return trianglesIntersect(toDouble(first), toDouble(second));
}

/// The least overlap of the two triangles' projections over `directions` unit vectors spread
/// over the sphere (a Fibonacci lattice): an upper bound on the penetration depth that closes on it
/// as the directions grow dense, found without knowing which axes matter.
double bruteForceDepth(const TriangleCorners& a, const TriangleCorners& b, int directions) {
  double depth = std::numeric_limits<double>::infinity();
  const double golden = std::acos(-1.0) * (3 - std::sqrt(5.0));
  for (int i = 0; i < directions; ++i) {
    const double z = 1 - 2 * (i + 0.5) / directions, r = std::sqrt(1 - z * z);
    const Vec3d unit(r * std::cos(golden * i), r * std::sin(golden * i), z);
    double lowA = 1e300, highA = -1e300, lowB = 1e300, highB = -1e300;
    for (int k = 0; k < 3; ++k) {
      lowA = std::min(lowA, unit.dot(a[k].cast<double>()));
      highA = std::max(highA, unit.dot(a[k].cast<double>()));
      lowB = std::min(lowB, unit.dot(b[k].cast<double>()));
      highB = std::max(highB, unit.dot(b[k].cast<double>()));
    }
    depth = std::min(depth, std::max(0.0, std::min(highA - lowB, highB - lowA)));
  }
  return depth;
}

TEST(PenetrationDepth, AStandingTriangleThroughAFloorPartsByItsShorterWayOut) {
  const TriangleCorners kFloor = {Vec3(0, 0, 0), Vec3(8, 0, 0), Vec3(0, 8, 0)};
  // Through the floor from z = −1 to z = 4: up by 1 parts them.
  const TriangleCorners standing = {Vec3(2, 2, -1), Vec3(2, 4, 4), Vec3(2, 2, 4)};
  EXPECT_NEAR(penetrationDepth(kFloor, standing), 1.0, 1e-12);
  EXPECT_NEAR(penetrationDepth(standing, kFloor), 1.0, 1e-12);
  // Lifted clear of the floor: apart.
  const TriangleCorners lifted = {Vec3(2, 2, 1), Vec3(2, 4, 4), Vec3(2, 2, 4)};
  EXPECT_EQ(penetrationDepth(kFloor, lifted), 0.0);
}

TEST(PenetrationDepth, FacesAtASlightAngleThatBarelyOverlapAreBarelyDeep) {
  // Tilted by 8° about a line across the floor, each reaches far past the other's plane (0.07
  // and 0.069 of the unit floor), but their planes meet just inside the floor's hypotenuse: a
  // nudge of about a thousandth parts them. Faces of an assembly fitted at a slight angle cross
  // so by rounding; a depth by the planes alone took them for 0.15 mm deep.
  const TriangleCorners floor = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const TriangleCorners tilted = {Vec3(0, 0.6f, -0.07f), Vec3(1, 0.398f, 0.07f),
                                  Vec3(1, 0.8f, 0.07f)};
  ASSERT_TRUE(referenceIntersects(floor, tilted));
  const double depth = penetrationDepth(floor, tilted);
  EXPECT_GT(depth, 0.0);
  EXPECT_LT(depth, 1e-3);
}

/// A triangle with corners drawn uniformly from the cube [−1, 1]³.
TriangleCorners randomTriangle(std::mt19937& random) {
  std::uniform_real_distribution<float> coordinate(-1, 1);
  TriangleCorners t;
  for (Vec3& p : t) p = Vec3(coordinate(random), coordinate(random), coordinate(random));
  return t;
}

TEST(PenetrationDepth, AgreesWithADenseSearchOverDirectionsOnRandomPairs) {
  std::mt19937 random(11);
  int crossing = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const TriangleCorners a = randomTriangle(random);
    const TriangleCorners b = randomTriangle(random);
    const double depth = penetrationDepth(a, b);
    const double searched = bruteForceDepth(a, b, 20000);
    // Every direction searched overlaps by at least the least one; 20 000 directions lie within
    // 0.03 rad of any, which moves an overlap of these triangles (within 2√3 across) by < 0.06.
    EXPECT_LE(depth, searched + 1e-9) << "trial " << trial;
    EXPECT_GE(depth, searched - 0.06) << "trial " << trial;
    if (referenceIntersects(a, b)) {
      ++crossing;
      EXPECT_GT(depth, 0.0) << "trial " << trial;
    } else {
      EXPECT_EQ(depth, 0.0) << "trial " << trial;
    }
  }
  EXPECT_GT(crossing, 30) << "both answers must be exercised";
}

/// The least distance between the points of a barycentric grid of `steps` per edge on each
/// triangle: at least the distance between the triangles, and at most 2·L/steps more (L the
/// longest edge), as every point of a triangle lies within L/steps of a grid point.
double sampledDistance(const TriangleCorners& a, const TriangleCorners& b, int steps) {
  const auto grid = [&](const TriangleCorners& t) {
    std::vector<Vec3d> points;
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j) {
        const double u = double(i) / steps, v = double(j) / steps;
        points.push_back((1 - u - v) * t[0].cast<double>() + u * t[1].cast<double>() +
                         v * t[2].cast<double>());
      }
    return points;
  };
  const std::vector<Vec3d> first = grid(a), second = grid(b);
  double least = std::numeric_limits<double>::infinity();
  for (const Vec3d& p : first)
    for (const Vec3d& q : second) least = std::min(least, (p - q).squaredNorm());
  return std::sqrt(least);
}

double longestEdge(const TriangleCorners& t) {
  return std::max(
      {double((t[1] - t[0]).norm()), double((t[2] - t[1]).norm()), double((t[0] - t[2]).norm())});
}

TEST(TriangleDistance, ParallelFacesAreTheirOffsetApartAndCrossingOnesZero) {
  const TriangleCorners floor = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  const TriangleCorners above = {Vec3(1, 1, 0.5f), Vec3(2, 1, 0.5f), Vec3(1, 2, 0.5f)};
  EXPECT_NEAR(triangleDistance(floor, above), 0.5, 1e-12);
  EXPECT_NEAR(triangleDistance(above, floor), 0.5, 1e-12);
  // An edge 0.25 under a face, the two planes at right angles.
  const TriangleCorners beside = {Vec3(5, -1, 0.25f), Vec3(5, 3, 0.25f), Vec3(7, 1, 0.25f)};
  const TriangleCorners crossing = {Vec3(4, 0.5f, 0), Vec3(6, 0.5f, 0), Vec3(5, 0.5f, -3)};
  EXPECT_NEAR(triangleDistance(beside, crossing), 0.25, 1e-7);
  // Standing through the floor: they meet.
  const TriangleCorners standing = {Vec3(1, 1, -1), Vec3(1, 2, 1), Vec3(1, 1, 1)};
  EXPECT_EQ(triangleDistance(floor, standing), 0.0);
}

TEST(TriangleDistance, AgreesWithDenseSamplingOnRandomPairs) {
  std::mt19937 random(13);
  int apart = 0;
  for (int trial = 0; trial < 120; ++trial) {
    const TriangleCorners a = randomTriangle(random);
    TriangleCorners b = randomTriangle(random);
    b[0].x() += 1.5f, b[1].x() += 1.5f, b[2].x() += 1.5f;  // about half of them apart
    constexpr int kSteps = 60;
    const double distance = triangleDistance(a, b);
    const double sampled = sampledDistance(a, b, kSteps);
    EXPECT_LE(distance, sampled + 1e-12) << "trial " << trial;
    EXPECT_GE(distance, sampled - (longestEdge(a) + longestEdge(b)) / kSteps) << "trial " << trial;
    if (referenceIntersects(a, b)) {
      EXPECT_EQ(distance, 0.0) << "trial " << trial;
    } else {
      apart += distance > 0;
    }
  }
  EXPECT_GT(apart, 30) << "both answers must be exercised";
}

TEST(TouchingWithinRounding, AFloatStepOffAFaceIsWithinItAndAMillimetreIsNot) {
  // The checker's own case (TouchingCountsAndOneStepAwayDoesNot): a corner one float step off the
  // other's plane is apart by the exact checker, and within rounding here.
  TriangleCorners floor = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  TriangleCorners standing = {Vec3(0.25f, 0.25f, 0), Vec3(0.3f, 0.2f, 1), Vec3(0.2f, 0.3f, 1)};
  EXPECT_TRUE(touchingWithinRounding(floor, standing));
  standing[0].z() = std::nextafter(0.0f, 1.0f);
  EXPECT_TRUE(touchingWithinRounding(floor, standing));
  standing[0].z() = 1e-3f;
  EXPECT_FALSE(touchingWithinRounding(floor, standing));
  // The rounding grows with the coordinates: 2 µm apart is within it 40 m from the origin (a float
  // there is 3.8 µm apart), and not at 1 m.
  for (Vec3& corner : floor) corner.x() += 40;
  for (Vec3& corner : standing) corner.x() += 40;
  standing[0].z() = 2e-6f;
  EXPECT_TRUE(touchingWithinRounding(floor, standing));
  for (Vec3& corner : floor) corner.x() -= 39;
  for (Vec3& corner : standing) corner.x() -= 39;
  EXPECT_FALSE(touchingWithinRounding(floor, standing));
}

}  // namespace
}  // namespace softbake::test
