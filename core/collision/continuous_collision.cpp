#include "core/collision/continuous_collision.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace softbake {

namespace {

/// A vector that changes linearly over the substep: v(t) = v0 + t·dv.
struct LinearVector {
  Vec3d v0, dv;
};

LinearVector difference(const PointPath& to, const PointPath& from) {
  return {to.start - from.start, (to.end - from.end) - (to.start - from.start)};
}

/// f(t) = (u × v) · w as c0 + c1·t + c2·t² + c3·t³.
struct Cubic {
  std::array<double, 4> c{};
  double operator()(double t) const { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; }
};

Cubic tripleProduct(const LinearVector& u, const LinearVector& v, const LinearVector& w) {
  const Vec3d a = u.v0.cross(v.v0);
  const Vec3d b = u.v0.cross(v.dv) + u.dv.cross(v.v0);
  const Vec3d c = u.dv.cross(v.dv);
  return {{a.dot(w.v0), a.dot(w.dv) + b.dot(w.v0), b.dot(w.dv) + c.dot(w.v0), c.dot(w.dv)}};
}

/// The times, in increasing order, at which the cubic may bring four points within the tolerance
/// of one plane: its roots in [0, 1], and the ends and extrema where |f| is within `fTolerance`.
/// Returns how many were written (at most 7: the ends, two extrema and three roots).
int candidateTimes(const Cubic& f, double fTolerance, std::array<double, 8>& times) {
  const std::array<double, 4>& c = f.c;
  // Bernstein coefficients on [0, 1]: f lies within their hull.
  const double b0 = c[0], b1 = c[0] + c[1] / 3, b2 = c[0] + (2 * c[1] + c[2]) / 3,
               b3 = c[0] + c[1] + c[2] + c[3];
  if (std::min({b0, b1, b2, b3}) > fTolerance || std::max({b0, b1, b2, b3}) < -fTolerance) return 0;
  // Extrema: roots of f' = c1 + 2c2·t + 3c3·t², split [0, 1] into pieces on which f is monotone.
  std::array<double, 4> breaks{0, 1, 1, 1};
  int breakCount = 1;
  const double qa = 3 * c[3], qb = 2 * c[2], qc = c[1];
  const auto addBreak = [&](double t) {
    if (t > 0 && t < 1) breaks[breakCount++] = t;
  };
  if (qa != 0) {
    const double discriminant = qb * qb - 4 * qa * qc;
    if (discriminant >= 0) {
      const double root = std::sqrt(discriminant);
      // The stable form: no cancellation between qb and the root.
      const double q = -0.5 * (qb + std::copysign(root, qb));
      addBreak(q / qa);
      if (q != 0) addBreak(qc / q);
    }
  } else if (qb != 0) {
    addBreak(-qc / qb);
  }
  if (breakCount == 3 && breaks[2] < breaks[1]) std::swap(breaks[1], breaks[2]);
  breaks[breakCount++] = 1;
  int count = 0;
  for (int i = 0; i < breakCount; ++i) {
    const double t = breaks[i];
    const double ft = f(t);
    if (std::abs(ft) <= fTolerance) times[count++] = t;
    if (i + 1 == breakCount) break;
    double lo = t, hi = breaks[i + 1], flo = ft;
    const double fhi = f(hi);
    if ((flo < 0) == (fhi < 0) || flo == 0 || fhi == 0) continue;
    // Bisection: f is monotone on the piece, so the bracket holds exactly one root.
    for (int k = 0; k < 52 && hi - lo > 1e-13; ++k) {
      const double mid = 0.5 * (lo + hi);
      const double fm = f(mid);
      if ((fm < 0) == (flo < 0)) {
        lo = mid;
        flo = fm;
      } else {
        hi = mid;
      }
    }
    times[count++] = 0.5 * (lo + hi);
  }
  // Already in increasing order: each piece adds its start, then its root inside it.
  return count;
}

/// A bound on |u × v| over the substep, |u|·|v| at their longest (a norm of a linear function is
/// largest at an end): the scale that turns a distance tolerance into one on the triple product.
/// Four norms, where the cross products themselves cost more than the rejection they serve.
double crossScale(const LinearVector& u, const LinearVector& v) {
  const double u2 = std::max(u.v0.squaredNorm(), (u.v0 + u.dv).squaredNorm());
  const double v2 = std::max(v.v0.squaredNorm(), (v.v0 + v.dv).squaredNorm());
  return std::sqrt(u2 * v2);
}

/// Points the normal from the second primitive to the first at the substep's start, where no
/// primitive has crossed yet.
void orientFromStart(Impact& impact, const std::array<const PointPath*, 4>& points) {
  Vec3d separation = Vec3d::Zero();
  for (int i = 0; i < 4; ++i) separation += impact.weight[i] * points[i]->start;
  if (impact.normal.dot(separation) < 0) impact.normal = -impact.normal;
}

/// The first candidate time of the cubic (u × v) · w at which `meetAt` finds the primitives within
/// the tolerance, its normal pointed from the second primitive to the first.
template <typename MeetAt>
std::optional<Impact> firstMeeting(const LinearVector& u, const LinearVector& v,
                                   const LinearVector& w, double tolerance,
                                   const std::array<const PointPath*, 4>& points, MeetAt meetAt) {
  const double scale = crossScale(u, v);
  if (scale == 0) return std::nullopt;
  std::array<double, 8> times;
  const int count = candidateTimes(tripleProduct(u, v, w), tolerance * scale, times);
  for (int i = 0; i < count; ++i)
    if (std::optional<Impact> impact = meetAt(times[i])) {
      orientFromStart(*impact, points);
      return impact;
    }
  return std::nullopt;
}

/// How far, at most, any point of one primitive moves relative to any point of the other over the
/// substep: the largest |Δx_i − Δx_j| over a point i of the first and a point j of the second
/// (their points are convex combinations of their corners, so no pair of points moves more).
template <std::size_t N, std::size_t M>
double mostRelativeTravel(const std::array<const PointPath*, N>& first,
                          const std::array<const PointPath*, M>& second) {
  double most = 0;
  for (const PointPath* i : first)
    for (const PointPath* j : second)
      most = std::max(most, ((i->end - i->start) - (j->end - j->start)).squaredNorm());
  return std::sqrt(most);
}

/// True when two primitives `startDistance` apart cannot come within `tolerance` over the substep:
/// their distance falls by at most their relative travel. Most candidate pairs of an assembly
/// whose parts move together end here, before the cubic, whose near-zero coefficients (fitted,
/// coplanar faces) the Bernstein bound cannot reject. The margin keeps rounding on the side of
/// testing.
bool outOfReach(double startDistance, double relativeTravel, double tolerance) {
  return startDistance > tolerance * (1 + 1e-6) + relativeTravel * (1 + 1e-9);
}

}  // namespace

Vec3d closestPointBarycentric(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denominator = va + vb + vc;
  if (denominator <= 0) return {1, 0, 0};  // a degenerate triangle: its first corner
  const double v = vb / denominator, w = vc / denominator;
  return {1 - v - w, v, w};
}

std::array<double, 2> closestSegmentParameters(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0,
                                               const Vec3d& q1) {
  const Vec3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const auto clamp01 = [](double x) { return std::clamp(x, 0.0, 1.0); };
  if (a <= 0 && e <= 0) return {0, 0};
  if (a <= 0) return {0, clamp01(f / e)};
  const double c = d1.dot(r);
  if (e <= 0) return {clamp01(-c / a), 0};
  const double b = d1.dot(d2), denominator = a * e - b * b;
  double s = denominator > 0 ? clamp01((b * f - c * e) / denominator) : 0;
  double u = (b * s + f) / e;
  if (u < 0) {
    u = 0;
    s = clamp01(-c / a);
  } else if (u > 1) {
    u = 1;
    s = clamp01((b - c) / a);
  }
  return {s, u};
}

double pointTriangleDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d w = closestPointBarycentric(p, a, b, c);
  return (p - (w[0] * a + w[1] * b + w[2] * c)).norm();
}

double segmentDistance(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0, const Vec3d& q1) {
  const std::array<double, 2> s = closestSegmentParameters(p0, p1, q0, q1);
  return ((p0 + s[0] * (p1 - p0)) - (q0 + s[1] * (q1 - q0))).norm();
}

double triangleDistance(const std::array<Vec3d, 3>& a, const std::array<Vec3d, 3>& b) {
  double distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    distance = std::min(distance, pointTriangleDistance(a[k], b[0], b[1], b[2]));
    distance = std::min(distance, pointTriangleDistance(b[k], a[0], a[1], a[2]));
    for (int j = 0; j < 3; ++j)
      distance = std::min(distance, segmentDistance(a[k], a[(k + 1) % 3], b[j], b[(j + 1) % 3]));
  }
  return distance;
}

std::optional<Impact> vertexFaceImpact(const PointPath& p, const PointPath& a, const PointPath& b,
                                       const PointPath& c, double tolerance) {
  if (outOfReach(pointTriangleDistance(p.start, a.start, b.start, c.start),
                 mostRelativeTravel<1, 3>({&p}, {&a, &b, &c}), tolerance))
    return std::nullopt;
  const LinearVector ab = difference(b, a), ac = difference(c, a), ap = difference(p, a);
  return firstMeeting(ab, ac, ap, tolerance, {&p, &a, &b, &c},
                      [&](double t) -> std::optional<Impact> {
                        const Vec3d pt = p.at(t), at = a.at(t), bt = b.at(t), ct = c.at(t);
                        const Vec3d bary = closestPointBarycentric(pt, at, bt, ct);
                        const Vec3d closest = bary[0] * at + bary[1] * bt + bary[2] * ct;
                        const Vec3d normal = (bt - at).cross(ct - at);
                        if ((pt - closest).norm() > tolerance || normal.squaredNorm() == 0)
                          return std::nullopt;
                        return Impact{t, {1, -bary[0], -bary[1], -bary[2]}, normal.normalized()};
                      });
}

std::optional<Impact> edgeEdgeImpact(const PointPath& p0, const PointPath& p1, const PointPath& q0,
                                     const PointPath& q1, double tolerance) {
  if (outOfReach(segmentDistance(p0.start, p1.start, q0.start, q1.start),
                 mostRelativeTravel<2, 2>({&p0, &p1}, {&q0, &q1}), tolerance))
    return std::nullopt;
  const LinearVector dp = difference(p1, p0), dq = difference(q1, q0), r = difference(q0, p0);
  return firstMeeting(
      dp, dq, r, tolerance, {&p0, &p1, &q0, &q1}, [&](double t) -> std::optional<Impact> {
        const Vec3d a0 = p0.at(t), a1 = p1.at(t), b0 = q0.at(t), b1 = q1.at(t);
        const Vec3d cross = (a1 - a0).cross(b1 - b0);
        // Nearly parallel edges have no well-defined normal; their ends' vertex–face tests see
        // them.
        if (cross.squaredNorm() <= 1e-12 * (a1 - a0).squaredNorm() * (b1 - b0).squaredNorm())
          return std::nullopt;
        const auto [s, u] = closestSegmentParameters(a0, a1, b0, b1);
        const Vec3d gap = (a0 + s * (a1 - a0)) - (b0 + u * (b1 - b0));
        if (gap.norm() > tolerance) return std::nullopt;
        return Impact{t, {1 - s, s, -(1 - u), -u}, cross.normalized()};
      });
}

}  // namespace softbake
