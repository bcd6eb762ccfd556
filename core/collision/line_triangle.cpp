#include "core/collision/line_triangle.hpp"

#include <cmath>

namespace softbake {

bool intersectSegmentTriangle(const Vec3& start, const Vec3& end, const Vec3& a, const Vec3& b,
                              const Vec3& c, SegmentTriangleHit& hit) {
  const Vec3 normal = (b - a).cross(c - a);
  return intersectSegmentTriangle(start, end, a, b, c, normal, normal.dot(start - a),
                                  normal.dot(end - a), hit);
}

bool intersectSegmentTriangle(const Vec3& start, const Vec3& end, const Vec3& a, const Vec3& b,
                              const Vec3& c, const Vec3& normal, Scalar startSide, Scalar endSide,
                              SegmentTriangleHit& hit) {
  // Both strictly on one side, or both on the plane (in-plane, or a degenerate triangle whose
  // normal is zero): no crossing.
  if ((startSide > 0 && endSide > 0) || (startSide < 0 && endSide < 0)) return false;
  if (startSide == endSide) return false;
  const Scalar t = startSide / (startSide - endSide);
  // An end on the plane is returned bit for bit (start + 1·(end − start) may round away from it):
  // the next edge of a triangle starts there, and its hit at t = 0 must be the same point so that
  // intersectEdgesWithTriangle sees one corner, not two points a rounding error apart.
  const Vec3 point = endSide == 0 ? end : start + t * (end - start);

  // Drop the axis of the normal's largest component and solve in the remaining two.
  int drop = 0;
  const Vec3 magnitude = normal.cwiseAbs();
  if (magnitude.y() > magnitude[drop]) drop = 1;
  if (magnitude.z() > magnitude[drop]) drop = 2;
  const int u = drop == 0 ? 1 : 0, v = drop == 2 ? 1 : 2;
  auto area2d = [u, v](const Vec3& p, const Vec3& q, const Vec3& r) {
    return (q[u] - p[u]) * (r[v] - p[v]) - (q[v] - p[v]) * (r[u] - p[u]);
  };
  const Scalar total = area2d(a, b, c);
  if (total == 0) return false;  // not reached for a non-degenerate normal; keeps NaN out
  const Scalar wa = area2d(point, b, c) / total;
  const Scalar wb = area2d(a, point, c) / total;
  const Scalar wc = area2d(a, b, point) / total;
  if (!(wa >= 0 && wb >= 0 && wc >= 0)) return false;
  hit.t = t;
  hit.point = point;
  hit.barycentric = Vec3(wa, wb, wc);
  return true;
}

}  // namespace softbake
