#pragma once
/// The line–triangle test of Mesit & Guha §2.3: where a segment crosses a triangle.
///
/// The segment is intersected with the triangle's plane; the crossing point is accepted when its
/// barycentric coordinates, computed in 2D after dropping the axis along which the plane's normal
/// is largest, are all ≥ 0. Dropping that axis keeps the projected triangle's area as large as
/// possible, so the 2D coordinates are as well conditioned as the 3D ones.
///
/// Conventions, chosen where the paper is silent:
/// - Closed segment and closed triangle: an endpoint on the plane and a point on an edge or vertex
///   count as hits. Two triangles that share the edge both report it; callers deduplicate by
///   point (see the response), so a hit is never counted twice.
/// - A segment lying in the plane (both endpoints at zero distance) does not cross the triangle:
///   no hit. Coplanar contact is caught by the other triangle's edges or the particle segments.
/// - A degenerate triangle (zero area) has no plane: no hit. Nothing divides by zero.

#include "core/types.hpp"

namespace softbake {

struct SegmentTriangleHit {
  Scalar t = 0;               ///< segment parameter of the crossing, 0 at `start`, 1 at `end`
  Vec3 point = Vec3::Zero();  ///< start + t·(end − start); exactly `start` or `end` at t = 0 or 1
  Vec3 barycentric = Vec3::Zero();  ///< weights of a, b, c at the point; each ≥ 0, sum 1
};

/// True when the closed segment start→end crosses the closed triangle abc; fills `hit`.
bool intersectSegmentTriangle(const Vec3& start, const Vec3& end, const Vec3& a, const Vec3& b,
                              const Vec3& c, SegmentTriangleHit& hit);

/// The same test where the caller has the triangle's normal, (b − a) × (c − a), and the segment's
/// ends' sides of its plane, normal · (start − a) and normal · (end − a), from a rejection of its
/// own: the same result, bit for bit, without computing them again.
bool intersectSegmentTriangle(const Vec3& start, const Vec3& end, const Vec3& a, const Vec3& b,
                              const Vec3& c, const Vec3& normal, Scalar startSide, Scalar endSide,
                              SegmentTriangleHit& hit);

}  // namespace softbake
