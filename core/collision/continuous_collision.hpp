#pragma once
/// Continuous collision tests (Provot 1997; Bridson, Fedkiw & Anderson 2002, §4): the first time in
/// a substep at which a vertex meets a moving triangle, or an edge meets another edge, when every
/// point moves on a straight line from its start to its end.
///
/// A pair whose distance at the start exceeds the tolerance by more than its points' relative
/// travel cannot meet, and is rejected first: an assembly's parts falling together move little
/// relative to each other. Four points are coplanar where the cubic
/// f(t) = ((x1 − x0) × (x2 − x0)) · (x3 − x0) vanishes. Its Bernstein coefficients bound it on
/// [0, 1], so most other primitive pairs are rejected by four numbers before any root is sought.
/// Otherwise the roots are bracketed between the extrema of the cubic and bisected, and at each in
/// time order the two primitives' true distance is measured: within `tolerance` is a hit.
/// Near-coplanar extrema that never reach zero are measured too, so a vertex grazing a face within
/// the tolerance is not lost to rounding. Everything is computed in double precision from the
/// (possibly single-precision) positions.
///
/// A hit carries the weights that turn the primitives' points into the contact point on each side
/// (a vertex: 1; a face: minus its barycentric coordinates; an edge: its end weights, negated on
/// the second edge), so Σ w_i·x_i is the separation vector and a change of Σ w_i·x_i along the
/// normal is what a response must make.

#include <array>
#include <optional>

#include "core/types.hpp"

namespace softbake {

using Vec3d = Eigen::Vector3d;

/// A point's motion over the substep.
struct PointPath {
  Vec3d start, end;
  Vec3d at(double t) const { return start + t * (end - start); }
};

struct Impact {
  double t = 0;                    ///< when, 0 at the substep's start and 1 at its end
  std::array<double, 4> weight{};  ///< per primitive point: Σ weight·x is the separation
  Vec3d normal = Vec3d::Zero();  ///< unit, pointing from the second primitive to the first at t = 0
};

/// Vertex `p` against triangle (a, b, c).
std::optional<Impact> vertexFaceImpact(const PointPath& p, const PointPath& a, const PointPath& b,
                                       const PointPath& c, double tolerance);

/// Edge (p0, p1) against edge (q0, q1). Parallel edges are left to the vertex–face tests of their
/// ends, which meet first.
std::optional<Impact> edgeEdgeImpact(const PointPath& p0, const PointPath& p1, const PointPath& q0,
                                     const PointPath& q1, double tolerance);

/// The barycentric weights of a, b, c at the foot of `x` on the plane of triangle abc (Ericson,
/// Real-Time Collision Detection, §3.4), unclamped: one is negative where the foot lies past the
/// edge opposite its corner. None for a triangle with no area. In float or double, as given.
template <class V>
std::optional<std::array<typename V::Scalar, 3>> footBarycentric(const V& a, const V& b, const V& c,
                                                                 const V& x) {
  using S = typename V::Scalar;
  const V ab = b - a, ac = c - a, ax = x - a;
  const S d00 = ab.dot(ab), d01 = ab.dot(ac), d11 = ac.dot(ac);
  const S d20 = ax.dot(ab), d21 = ax.dot(ac);
  const S denominator = d00 * d11 - d01 * d01;
  if (!(denominator > 0)) return std::nullopt;
  const S beta = (d11 * d20 - d01 * d21) / denominator;
  const S gamma = (d00 * d21 - d01 * d20) / denominator;
  return std::array<S, 3>{1 - beta - gamma, beta, gamma};
}

/// The closest point of triangle abc to p, as barycentric weights of a, b, c (Ericson,
/// Real-Time Collision Detection, §5.1.5).
Vec3d closestPointBarycentric(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// Parameters (s, u) of the closest points p0 + s(p1 − p0) and q0 + u(q1 − q0) of two segments
/// (Ericson §5.1.9).
std::array<double, 2> closestSegmentParameters(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0,
                                               const Vec3d& q1);

/// Distance from p to triangle abc.
double pointTriangleDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);
/// Distance between segments p0p1 and q0q1.
double segmentDistance(const Vec3d& p0, const Vec3d& p1, const Vec3d& q0, const Vec3d& q1);
/// Distance between two triangles that do not intersect: the least of their six vertex–face and
/// nine edge–edge distances (for intersecting ones this is not 0).
double triangleDistance(const std::array<Vec3d, 3>& a, const std::array<Vec3d, 3>& b);

}  // namespace softbake
