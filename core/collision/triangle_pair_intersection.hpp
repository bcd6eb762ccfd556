#pragma once
/// The paper's multi-pass line–triangle test (§2.3) for one candidate triangle pair.
///
/// The three edges of one triangle are tested against the other triangle with
/// intersectSegmentTriangle, one edge per pass; the test stops after two hits, since two points
/// fix the line along which two triangles cross. Then the same is done the other way round.
///
/// What counts as one hit (the paper is silent; these keep the count a count of points):
/// - Within one direction no point is reported twice. An edge through a vertex or along an edge
///   of the face is one segment test, so one hit. A corner of the edge triangle that lies exactly
///   on the face's plane is the end of one edge (t = 1) and the start of the next (t = 0);
///   intersectSegmentTriangle returns that corner bit for bit both times, and a hit equal to one
///   already recorded is dropped, so the corner is reported once, by the first edge in pass order.
///   A dropped duplicate does not use up one of the two slots.
/// - Between the two directions nothing is merged: two triangles touching at a shared vertex give
///   one hit each way, at the same point. The response deduplicates by point.
/// - A zero-area edge triangle (cross product exactly zero: collinear or coincident corners) is
///   a segment that all three edges run along; only its longest edge is tested, so a crossing is
///   one hit, not two or three copies a rounding error apart. Zero-length edges never hit. A
///   zero-area face has no plane and is never hit, so a collapsed triangle can still be found by
///   its edge piercing a proper triangle, but two collapsed triangles never intersect.
/// - Coplanar triangles are not reported, even when they overlap: in-plane edges do not cross the
///   face (see line_triangle.hpp). Triangles meeting in a line across each other's interior are.
/// Hit points that are distinct in the float geometry but a rounding error apart (an edge triangle
/// corner a hair off the face's plane) are both kept: merging by tolerance would need a length
/// scale the test does not have, and the two points are genuine.

#include <array>
#include <cstdint>

#include "core/collision/line_triangle.hpp"
#include "core/types.hpp"

namespace softbake {

using TriangleCorners = std::array<Vec3, 3>;

struct EdgeHit {
  SegmentTriangleHit hit;  ///< where the edge crosses the face; t along corner e → corner (e+1)%3
  std::uint8_t edge = 0;   ///< which edge of the edge triangle
};

/// Edges of `edgeTriangle` against the face `face`, pass by pass, stopping after two hits.
/// Returns the number of hits (0, 1 or 2) written to `hits`, in edge order.
int intersectEdgesWithTriangle(const TriangleCorners& edgeTriangle, const TriangleCorners& face,
                               std::array<EdgeHit, 2>& hits);

/// A triangle's normal, unnormalised, as every test here computes it: (b − a) × (c − a).
inline Vec3 triangleNormal(const TriangleCorners& t) {
  return (t[1] - t[0]).cross(t[2] - t[0]);
}

/// The side of the face's plane each corner lies on: faceNormal · (corner − face[0]).
inline std::array<Scalar, 3> sidesOfPlane(const TriangleCorners& corners,
                                          const TriangleCorners& face, const Vec3& faceNormal) {
  return {faceNormal.dot(corners[0] - face[0]), faceNormal.dot(corners[1] - face[0]),
          faceNormal.dot(corners[2] - face[0])};
}

/// The same test from what a caller has already computed: both triangles' triangleNormal() and
/// the edge triangle's corners' sidesOfPlane() of the face. The narrow phase computes them once per
/// pair for this test and for its particles' segments; the result is the same, bit for bit.
int intersectEdgesWithTriangle(const TriangleCorners& edgeTriangle, const Vec3& edgeNormal,
                               const TriangleCorners& face, const Vec3& faceNormal,
                               const std::array<Scalar, 3>& sides, std::array<EdgeHit, 2>& hits);

/// Both directions: `firstEdges` are edges of `first` through `second`, `secondEdges` edges of
/// `second` through `first`. True when any hit was found: the triangles intersect.
struct TrianglePairHits {
  std::array<EdgeHit, 2> firstEdges, secondEdges;
  int firstCount = 0, secondCount = 0;
};
bool intersectTrianglePair(const TriangleCorners& first, const TriangleCorners& second,
                           TrianglePairHits& hits);

}  // namespace softbake
