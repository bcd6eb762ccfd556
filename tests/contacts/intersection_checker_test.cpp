// The exact intersection checker (tests/support/intersection_checker) against an independent
// reference (Möller's interval test in double, tests/support/exact_geometry.hpp) wherever that
// reference is clear of rounding, and by hand where only exact arithmetic can tell.
#include "tests/support/intersection_checker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

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

}  // namespace
}  // namespace softbake::test
