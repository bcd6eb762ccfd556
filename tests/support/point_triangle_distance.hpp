#pragma once
// The distance from a point to a triangle, by brute force in double precision: the projection onto
// the plane when it falls inside, else the nearest of the three edges. A reference for the tests,
// written apart from core/collision's closest-point code.

#include <algorithm>
#include <limits>
#include <utility>

#include "core/types.hpp"

namespace softbake::test {

inline double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  using Vec = Eigen::Vector3d;
  const Vec n = (b - a).cross(c - a).normalized();
  const Vec q = p - n.dot(p - a) * n;
  const auto inside = [&](const Vec& x, const Vec& y) { return (y - x).cross(q - x).dot(n); };
  double best = std::numeric_limits<double>::infinity();
  if (inside(a, b) >= 0 && inside(b, c) >= 0 && inside(c, a) >= 0) best = (p - q).norm();
  for (const auto& [x, y] : {std::pair(a, b), std::pair(b, c), std::pair(c, a)}) {
    const double s = std::clamp((p - x).dot(y - x) / (y - x).squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (x + s * (y - x))).norm());
  }
  return best;
}

}  // namespace softbake::test
