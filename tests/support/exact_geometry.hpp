#pragma once
/// Double-precision references for the narrow-phase tests, written independently of
/// core/collision/line_triangle and core/collision/triangle_pair_intersection so that the two can
/// be checked against each other:
/// - mollerTrumbore: segment–triangle intersection (Möller & Trumbore 1997, "Fast, minimum storage
///   ray/triangle intersection"), closed segment and closed triangle.
/// - trianglesIntersect: triangle–triangle intersection by interval overlap on the line where the
///   two planes meet (Möller 1997, "A fast triangle-triangle intersection test"), closed
///   triangles, with coplanar triangles decided by an exact-zero test and a 2D overlap test.
/// - segmentTriangleBand / classifyTrianglePair: whether float rounding in the code under test
///   may flip a decision, so that tests can tell a genuine disagreement from one in the rounding
///   band.
///
/// Inputs are float positions widened to double, so differences are exact and products nearly
/// so: the references are "exact" in the sense that their own error is about 2^-29 of the float
/// code's. No epsilon is applied inside them; zero means computed zero.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/types.hpp"

namespace softbake::test {

using TriangleD = std::array<Vec3d, 3>;

inline TriangleD toDouble(const std::array<Vec3, 3>& t) {
  return {t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>()};
}

// ---------------------------------------------------------------------------------------------
// Segment–triangle

struct ReferenceSegmentHit {
  bool hit = false;
  double t = 0;                       ///< 0 at start, 1 at end
  Vec3d point = Vec3d::Zero();        ///< start + t·(end − start)
  Vec3d barycentric = Vec3d::Zero();  ///< weights of a, b, c
};

/// Möller–Trumbore, closed (t, u, v on their bounds count). A segment parallel to the plane
/// (det = 0) never hits, in the plane or not, and neither does a zero-area triangle: the same
/// conventions as intersectSegmentTriangle, so that only rounding can separate the two.
inline ReferenceSegmentHit mollerTrumbore(const Vec3d& start, const Vec3d& end, const Vec3d& a,
                                          const Vec3d& b, const Vec3d& c) {
  ReferenceSegmentHit result;
  const Vec3d direction = end - start, e1 = b - a, e2 = c - a;
  const Vec3d p = direction.cross(e2);
  const double det = e1.dot(p);
  if (det == 0) return result;
  const double inverse = 1 / det;
  const Vec3d s = start - a;
  const double u = s.dot(p) * inverse;
  if (u < 0 || u > 1) return result;
  const Vec3d q = s.cross(e1);
  const double v = direction.dot(q) * inverse;
  if (v < 0 || u + v > 1) return result;
  const double t = e2.dot(q) * inverse;
  if (t < 0 || t > 1) return result;
  result.hit = true;
  result.t = t;
  result.point = start + t * direction;
  result.barycentric = Vec3d(1 - u - v, u, v);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Distances (Ericson, "Real-Time Collision Detection", §5.1), safe for zero-length segments and
// zero-area triangles.

inline double pointSegmentDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

inline double segmentSegmentDistance(const Vec3d& p1, const Vec3d& q1, const Vec3d& p2,
                                     const Vec3d& q2) {
  const Vec3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  if (a == 0) return pointSegmentDistance(p1, p2, q2);
  if (e == 0) return pointSegmentDistance(p2, p1, q1);
  const double b = d1.dot(d2), c = d1.dot(r);
  const double denominator = a * e - b * b;
  // Parallel segments: any s works, so start from s = 0 and let the clamping below fix t and s.
  double s = denominator > 0 ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1) {
    t = 1;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  return (p1 + s * d1 - (p2 + t * d2)).norm();
}

inline double pointTriangleDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b,
                                    const Vec3d& c) {
  const Vec3d n = (b - a).cross(c - a);
  const double area2 = n.norm();
  // Inside the prism over the triangle the plane is nearest; outside it, the boundary is.
  if (area2 > 0 && n.dot((b - a).cross(p - a)) >= 0 && n.dot((c - b).cross(p - b)) >= 0 &&
      n.dot((a - c).cross(p - c)) >= 0)
    return std::abs(n.dot(p - a)) / area2;
  return std::min({pointSegmentDistance(p, a, b), pointSegmentDistance(p, b, c),
                   pointSegmentDistance(p, c, a)});
}

/// Distance between a closed segment and a closed triangle; 0 when they meet (also in-plane).
inline double segmentTriangleDistance(const Vec3d& start, const Vec3d& end, const Vec3d& a,
                                      const Vec3d& b, const Vec3d& c) {
  if (mollerTrumbore(start, end, a, b, c).hit) return 0;
  // Disjoint: the closest pair has an endpoint of the segment or a point of a triangle edge.
  return std::min({pointTriangleDistance(start, a, b, c), pointTriangleDistance(end, a, b, c),
                   segmentSegmentDistance(start, end, a, b),
                   segmentSegmentDistance(start, end, b, c),
                   segmentSegmentDistance(start, end, c, a)});
}

// ---------------------------------------------------------------------------------------------
// Triangle–triangle (Möller 1997)

namespace detail {

inline double orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                       const Eigen::Vector2d& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

inline bool onSegment2d(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

/// Closed segments, collinear overlap included.
inline bool segmentsIntersect2d(const Eigen::Vector2d& p1, const Eigen::Vector2d& q1,
                                const Eigen::Vector2d& p2, const Eigen::Vector2d& q2) {
  const double o1 = orient2d(p1, q1, p2), o2 = orient2d(p1, q1, q2);
  const double o3 = orient2d(p2, q2, p1), o4 = orient2d(p2, q2, q1);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return true;
  return (o1 == 0 && onSegment2d(p2, p1, q1)) || (o2 == 0 && onSegment2d(q2, p1, q1)) ||
         (o3 == 0 && onSegment2d(p1, p2, q2)) || (o4 == 0 && onSegment2d(q1, p2, q2));
}

/// Closed triangle of either winding.
inline bool pointInTriangle2d(const Eigen::Vector2d& p, const std::array<Eigen::Vector2d, 3>& t) {
  const double d0 = orient2d(t[0], t[1], p), d1 = orient2d(t[1], t[2], p),
               d2 = orient2d(t[2], t[0], p);
  return (d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0);
}

/// The two coordinates kept when projecting along `normal`'s largest axis: an affine map of the
/// plane, so it preserves overlap and containment.
inline std::array<int, 2> projectionAxes(const Vec3d& normal) {
  int drop = 0;
  const Vec3d magnitude = normal.cwiseAbs();
  if (magnitude.y() > magnitude[drop]) drop = 1;
  if (magnitude.z() > magnitude[drop]) drop = 2;
  return {drop == 0 ? 1 : 0, drop == 2 ? 1 : 2};
}

inline std::array<Eigen::Vector2d, 3> project(const TriangleD& t, const std::array<int, 2>& axes) {
  std::array<Eigen::Vector2d, 3> projected;
  for (int k = 0; k < 3; ++k) projected[k] = {t[k][axes[0]], t[k][axes[1]]};
  return projected;
}

/// Both proper triangles in the plane with normal `normal`: edges pairwise, plus containment.
inline bool coplanarTrianglesIntersect(const Vec3d& normal, const TriangleD& v,
                                       const TriangleD& u) {
  const std::array<int, 2> axes = projectionAxes(normal);
  const std::array<Eigen::Vector2d, 3> v2 = project(v, axes), u2 = project(u, axes);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segmentsIntersect2d(v2[i], v2[(i + 1) % 3], u2[j], u2[(j + 1) % 3])) return true;
  return pointInTriangle2d(v2[0], u2) || pointInTriangle2d(u2[0], v2);
}

/// Closed segment against a proper triangle, including a segment lying in its plane.
inline bool segmentMeetsTriangle(const Vec3d& start, const Vec3d& end, const TriangleD& t) {
  if (mollerTrumbore(start, end, t[0], t[1], t[2]).hit) return true;
  const Vec3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  if (n.dot(start - t[0]) != 0 || n.dot(end - t[0]) != 0) return false;
  const std::array<int, 2> axes = projectionAxes(n);
  const std::array<Eigen::Vector2d, 3> t2 = project(t, axes);
  const Eigen::Vector2d s2(start[axes[0]], start[axes[1]]), e2(end[axes[0]], end[axes[1]]);
  for (int j = 0; j < 3; ++j)
    if (segmentsIntersect2d(s2, e2, t2[j], t2[(j + 1) % 3])) return true;
  return pointInTriangle2d(s2, t2);
}

/// Möller's interval on the intersection line: the two points where the edges of a triangle
/// cross the other plane, projected on the line's largest axis. `d` are the corners' signed
/// distances (scaled) to the other plane; not all zero, not all of one strict sign.
inline std::array<double, 2> lineInterval(const std::array<double, 3>& p,
                                          const std::array<double, 3>& d) {
  // The corner alone on its side of the plane (or, with corners on the plane, the right one to
  // interpolate from): both of its edges reach the plane.
  int alone;
  if (d[0] * d[1] > 0)
    alone = 2;
  else if (d[0] * d[2] > 0)
    alone = 1;
  else if (d[1] * d[2] > 0 || d[0] != 0)
    alone = 0;
  else if (d[1] != 0)
    alone = 1;
  else
    alone = 2;
  const int k1 = (alone + 1) % 3, k2 = (alone + 2) % 3;
  std::array<double, 2> interval = {p[alone] + (p[k1] - p[alone]) * d[alone] / (d[alone] - d[k1]),
                                    p[alone] + (p[k2] - p[alone]) * d[alone] / (d[alone] - d[k2])};
  if (interval[0] > interval[1]) std::swap(interval[0], interval[1]);
  return interval;
}

}  // namespace detail

/// True when the closed triangles v and u share a point.
/// - Proper, non-coplanar: Möller's interval overlap. Touching (a shared vertex, a vertex on a
///   face) counts.
/// - Coplanar (every corner of one at computed distance exactly 0 from the other's plane, or
///   parallel normals with corners on both sides): 2D overlap, touching included. This differs
///   on purpose from the code under test, which does not report coplanar contact.
/// - One zero-area triangle: the union of its edges against the other, in-plane segments
///   included. Two zero-area triangles: false, by convention (the code never reports them).
inline bool trianglesIntersect(const TriangleD& v, const TriangleD& u) {
  const Vec3d nv = (v[1] - v[0]).cross(v[2] - v[0]);
  const Vec3d nu = (u[1] - u[0]).cross(u[2] - u[0]);
  const bool vFlat = nv == Vec3d::Zero(), uFlat = nu == Vec3d::Zero();
  if (vFlat && uFlat) return false;
  if (vFlat || uFlat) {
    const TriangleD& segments = vFlat ? v : u;
    const TriangleD& face = vFlat ? u : v;
    for (int k = 0; k < 3; ++k)
      if (detail::segmentMeetsTriangle(segments[k], segments[(k + 1) % 3], face)) return true;
    return false;
  }

  std::array<double, 3> du, dv;
  for (int k = 0; k < 3; ++k) {
    du[k] = nv.dot(u[k] - v[0]);
    dv[k] = nu.dot(v[k] - u[0]);
  }
  auto oneSide = [](const std::array<double, 3>& d) {
    return (d[0] > 0 && d[1] > 0 && d[2] > 0) || (d[0] < 0 && d[1] < 0 && d[2] < 0);
  };
  if (oneSide(du) || oneSide(dv)) return false;
  const Vec3d line = nv.cross(nu);
  if ((du[0] == 0 && du[1] == 0 && du[2] == 0) || (dv[0] == 0 && dv[1] == 0 && dv[2] == 0) ||
      line == Vec3d::Zero())
    return detail::coplanarTrianglesIntersect(nv, v, u);

  int axis = 0;
  const Vec3d magnitude = line.cwiseAbs();
  if (magnitude.y() > magnitude[axis]) axis = 1;
  if (magnitude.z() > magnitude[axis]) axis = 2;
  const std::array<double, 2> iv = detail::lineInterval({v[0][axis], v[1][axis], v[2][axis]}, dv);
  const std::array<double, 2> iu = detail::lineInterval({u[0][axis], u[1][axis], u[2][axis]}, du);
  return !(iv[1] < iu[0] || iu[1] < iv[0]);
}

// ---------------------------------------------------------------------------------------------
// Rounding bands

/// How far float rounding in intersectSegmentTriangle can move its decision.
struct SegmentTriangleBand {
  bool ambiguous = false;     ///< rounding may flip hit/miss: the exact answer is not binding
  double pointTolerance = 0;  ///< bound on |computed hit point − exact hit point|
};

/// The band, from a first-order error analysis with `relativeEpsilon` = K·(unit round-off of the
/// code's scalar). The float test works on differences of positions, so its plane distances and
/// 2D areas are off by a few ulps of the extent R of the inputs (their bounding-box diagonal),
/// magnified through the normal's direction by the triangle's conditioning
/// κ = (longest edge)²/(2·area) (≥ 1/sin of its smallest angle). Only the hit point
/// start + t·(end − start) is rounded to an ulp of the largest coordinate L. Hence
///   δ = relativeEpsilon · R · (1 + κ)                            plane-distance error
///   τ = relativeEpsilon · L + δ · (1 + |end − start| / |h0 − h1|)  hit-point error
/// where h0, h1 are the endpoints' distances to the plane: t = h0/(h0 − h1) loses accuracy as the
/// segment grazes the plane. The decision is ambiguous when an endpoint is within δ of the plane
/// and the segment passes within τ of the triangle, or the segment crosses the plane and the
/// crossing is within τ of the triangle's boundary. A zero-area triangle is always ambiguous:
/// its float normal need not be zero.
inline SegmentTriangleBand segmentTriangleBand(const Vec3d& start, const Vec3d& end, const Vec3d& a,
                                               const Vec3d& b, const Vec3d& c,
                                               double relativeEpsilon) {
  SegmentTriangleBand band;
  const Vec3d n = (b - a).cross(c - a);
  const double area2 = n.norm();
  if (area2 == 0) {
    band.ambiguous = true;
    band.pointTolerance = std::numeric_limits<double>::infinity();
    return band;
  }
  Vec3d low = start, high = start;
  for (const Vec3d* p : {&end, &a, &b, &c}) {
    low = low.cwiseMin(*p);
    high = high.cwiseMax(*p);
  }
  const double extent = (high - low).norm();
  const double largest = std::max(low.cwiseAbs().maxCoeff(), high.cwiseAbs().maxCoeff());
  const double longest2 =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  const double delta = relativeEpsilon * extent * (1 + longest2 / area2);
  const Vec3d unit = n / area2;
  const double h0 = unit.dot(start - a), h1 = unit.dot(end - a);
  band.pointTolerance = relativeEpsilon * largest +
                        delta * (1 + (end - start).norm() / std::max(std::abs(h0 - h1), delta));
  if (std::abs(h0) > delta && std::abs(h1) > delta) {
    if ((h0 > 0) == (h1 > 0)) return band;  // both clearly on one side
    const Vec3d crossing = start + h0 / (h0 - h1) * (end - start);
    const double toBoundary =
        std::min({pointSegmentDistance(crossing, a, b), pointSegmentDistance(crossing, b, c),
                  pointSegmentDistance(crossing, c, a)});
    band.ambiguous = toBoundary <= band.pointTolerance;
    return band;
  }
  band.ambiguous = segmentTriangleDistance(start, end, a, b, c) <= band.pointTolerance;
  return band;
}

enum class PairVerdict {
  Disjoint,      ///< no intersection, and no edge comes within rounding of the other triangle
  Intersecting,  ///< an edge crosses the other triangle clear of every rounding band
  Ambiguous,     ///< the float edge test may go either way
  Inconsistent,  ///< the two double references disagree outside the band: a reference bug
};

/// Möller's verdict, made binding only where the six edge–face tests in double are clear of the
/// band: an intersection is certain when some edge crosses the other face robustly, and absence
/// is certain when no edge is near the other face. Between the two the float test may differ.
inline PairVerdict classifyTrianglePair(const TriangleD& first, const TriangleD& second,
                                        double relativeEpsilon) {
  bool robustHit = false, nearMiss = false;
  for (int direction = 0; direction < 2; ++direction) {
    const TriangleD& edges = direction == 0 ? first : second;
    const TriangleD& face = direction == 0 ? second : first;
    for (int e = 0; e < 3; ++e) {
      const Vec3d &start = edges[e], &end = edges[(e + 1) % 3];
      const SegmentTriangleBand band =
          segmentTriangleBand(start, end, face[0], face[1], face[2], relativeEpsilon);
      if (band.ambiguous)
        nearMiss = true;
      else if (mollerTrumbore(start, end, face[0], face[1], face[2]).hit)
        robustHit = true;
    }
  }
  const bool intersect = trianglesIntersect(first, second);
  if (intersect && robustHit) return PairVerdict::Intersecting;
  if (!intersect && !robustHit && !nearMiss) return PairVerdict::Disjoint;
  if (intersect ? nearMiss : !robustHit) return PairVerdict::Ambiguous;
  return PairVerdict::Inconsistent;
}

}  // namespace softbake::test
