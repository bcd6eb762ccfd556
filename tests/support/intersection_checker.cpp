#include "tests/support/intersection_checker.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "tests/support/exact_geometry.hpp"

namespace softbake::test {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

bool shareAVertex(const Triangle& a, const Triangle& b) {
  for (Index u : a)
    for (Index v : b)
      if (u == v) return true;
  return false;
}

std::array<Vec3d, 3> inDouble(const TriangleCorners& t) {
  return {t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>()};
}
}  // namespace

IntersectionCount countIntersectingPairs(const CollisionGeometry& geometry,
                                         std::span<const Vec3> positions) {
  const std::size_t count = geometry.triangleVertices.size();
  std::vector<Kernel::Triangle_3> triangles;
  std::vector<Eigen::AlignedBox3d> boxes(count);
  triangles.reserve(count);
  for (std::size_t t = 0; t < count; ++t) {
    std::array<Kernel::Point_3, 3> corner;
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = geometry.vertex(positions, geometry.triangleVertices[t][k]).cast<double>();
      corner[k] = Kernel::Point_3(p.x(), p.y(), p.z());
      boxes[t].extend(p);
    }
    triangles.emplace_back(corner[0], corner[1], corner[2]);
  }
  // Sweep along x: the triangles in order of their boxes' lower x; each is tested against the
  // following ones until their lower x passes its upper x.
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return boxes[a].min().x() < boxes[b].min().x(); });
  IntersectionCount result;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t a = order[i];
    if (triangles[a].is_degenerate()) continue;
    for (std::size_t j = i + 1; j < count; ++j) {
      const std::size_t b = order[j];
      if (boxes[b].min().x() > boxes[a].max().x()) break;
      if (!boxes[a].intersects(boxes[b]) || triangles[b].is_degenerate()) continue;
      const Index surfaceA = geometry.triangleSurface[a], surfaceB = geometry.triangleSurface[b];
      const bool within = surfaceA == surfaceB;
      if (within && shareAVertex(geometry.triangleVertices[a], geometry.triangleVertices[b]))
        continue;
      if (!CGAL::do_intersect(triangles[a], triangles[b])) continue;
      (within ? result.withinSurfaces : result.betweenSurfaces) += 1;
      ++result.bySurfaces[{std::min(surfaceA, surfaceB), std::max(surfaceA, surfaceB)}];
      result.pairs.emplace_back(Index(std::min(a, b)), Index(std::max(a, b)));
    }
  }
  std::sort(result.pairs.begin(), result.pairs.end());
  return result;
}

double penetrationDepth(const TriangleCorners& a, const TriangleCorners& b) {
  const std::array<Vec3d, 3> p = inDouble(a), q = inDouble(b);
  double depth = std::numeric_limits<double>::infinity();
  const auto along = [&](const Vec3d& axis) {
    const double length = axis.norm();
    if (!(length > 0)) return;
    double lowP = std::numeric_limits<double>::infinity(), highP = -lowP, lowQ = lowP,
           highQ = -lowP;
    for (int k = 0; k < 3; ++k) {
      const double x = axis.dot(p[k]) / length, y = axis.dot(q[k]) / length;
      lowP = std::min(lowP, x);
      highP = std::max(highP, x);
      lowQ = std::min(lowQ, y);
      highQ = std::max(highQ, y);
    }
    depth = std::min(depth, std::min(highP - lowQ, highQ - lowP));
  };
  const Vec3d normalP = (p[1] - p[0]).cross(p[2] - p[0]);
  const Vec3d normalQ = (q[1] - q[0]).cross(q[2] - q[0]);
  along(normalP);
  along(normalQ);
  // Within each plane, across each edge: what parts triangles in one plane (faces fitted flat
  // onto each other), where every cross product of edges is the shared normal.
  for (int k = 0; k < 3; ++k) {
    along(normalP.cross(p[(k + 1) % 3] - p[k]));
    along(normalQ.cross(q[(k + 1) % 3] - q[k]));
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3d e = p[(i + 1) % 3] - p[i], f = q[(j + 1) % 3] - q[j];
      const Vec3d axis = e.cross(f);
      // Nearly parallel edges: their cross product is all rounding, and the normals cover them.
      if (axis.norm() > 1e-9 * e.norm() * f.norm()) along(axis);
    }
  return std::isfinite(depth) ? std::max(depth, 0.0) : 0.0;
}

double triangleDistance(const TriangleCorners& a, const TriangleCorners& b) {
  const std::array<Vec3d, 3> p = inDouble(a), q = inDouble(b);
  // Two triangles that do not meet are nearest at a corner of one or at a point of an edge of
  // each: an edge of one against the other triangle covers both.
  double distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    distance = std::min(distance, segmentTriangleDistance(p[k], p[(k + 1) % 3], q[0], q[1], q[2]));
    distance = std::min(distance, segmentTriangleDistance(q[k], q[(k + 1) % 3], p[0], p[1], p[2]));
  }
  return distance;
}

std::array<int, 2> edgesThrough(const TriangleCorners& a, const TriangleCorners& b) {
  const std::array<Vec3d, 3> p = inDouble(a), q = inDouble(b);
  std::array<int, 2> count{0, 0};
  for (int k = 0; k < 3; ++k) {
    count[0] += detail::segmentMeetsTriangle(p[k], p[(k + 1) % 3], q);
    count[1] += detail::segmentMeetsTriangle(q[k], q[(k + 1) % 3], p);
  }
  return count;
}

bool touchingWithinRounding(const TriangleCorners& a, const TriangleCorners& b) {
  double largest = 0;
  for (const TriangleCorners* corners : {&a, &b})
    for (const Vec3& corner : *corners)
      largest = std::max(largest, double(corner.cwiseAbs().maxCoeff()));
  return triangleDistance(a, b) <=
         kTouchingSpacings * double(std::numeric_limits<float>::epsilon()) * largest;
}

}  // namespace softbake::test
