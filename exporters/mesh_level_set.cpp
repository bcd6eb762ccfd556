#include "exporters/mesh_level_set.hpp"

#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

using openvdb::Vec3s;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;
using VelocityLeaf = openvdb::Vec3STree::LeafNodeType;
static_assert(FloatLeaf::DIM == 8 && VelocityLeaf::DIM == 8, "the leaf bricks below are 8³");

constexpr int kLeafLog2 = 3;
constexpr int kLeafMask = (1 << kLeafLog2) - 1;
/// Leaf coordinates are packed into 21 bits each for the sort key.
constexpr float kMaxCoordinate = float(1 << 22);
constexpr std::int64_t kKeyOffset = std::int64_t(1) << 20;

/// The Voronoi region of a triangle that holds the nearest point: which feature it lies on.
enum class Feature : std::uint8_t { Face, VertexA, VertexB, VertexC, EdgeAB, EdgeBC, EdgeCA };

struct NearestPoint {
  float u, v, w;  ///< barycentric weights of a, b, c
  Feature feature;
};

/// Ericson, "Real-Time Collision Detection", §5.1.5, keeping the region it ends in. A degenerate
/// triangle can give non-finite weights; its distance then compares false and never wins.
NearestPoint nearestOnTriangle(const Vec3s& p, const Vec3s& a, const Vec3s& b, const Vec3s& c) {
  const Vec3s ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0, Feature::VertexA};
  const Vec3s bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0, Feature::VertexB};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const float t = d1 / (d1 - d3);
    return {1 - t, t, 0, Feature::EdgeAB};
  }
  const Vec3s cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1, Feature::VertexC};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const float t = d2 / (d2 - d6);
    return {1 - t, 0, t, Feature::EdgeCA};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const float t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - t, t, Feature::EdgeBC};
  }
  const float scale = 1 / (va + vb + vc);
  const float v = vb * scale, w = vc * scale;
  return {1 - v - w, v, w, Feature::Face};
}

/// What the leaf fill reads per triangle, gathered once per frame.
struct TriangleGeometry {
  Vec3s a, b, c;
  Vec3s normal;  ///< unit, or zero for a degenerate triangle
  Vec3s centre;  ///< of the corners; with `radius`, a sphere holding the triangle
  float radius;
  openvdb::Coord lo, hi;  ///< the voxels that can lie within the band of it (inclusive)

  /// How many 8³ leaves lo..hi spans.
  std::size_t leafCount() const {
    std::size_t leaves = 1;
    for (int axis = 0; axis < 3; ++axis)
      leaves *= std::size_t((hi[axis] >> kLeafLog2) - (lo[axis] >> kLeafLog2) + 1);
    return leaves;
  }
};

/// The triangle's corners, normal, bounding sphere and reach (`band` voxels around its box).
TriangleGeometry triangleGeometry(const Vec3s& a, const Vec3s& b, const Vec3s& c, float band) {
  TriangleGeometry g;
  g.a = a;
  g.b = b;
  g.c = c;
  const Vec3s n = (b - a).cross(c - a);
  const float length = n.length();
  g.normal = length > 0 ? n / length : Vec3s(0.0f);
  g.centre = (a + b + c) / 3.0f;
  g.radius = std::sqrt(std::max(
      {(a - g.centre).lengthSqr(), (b - g.centre).lengthSqr(), (c - g.centre).lengthSqr()}));
  for (int axis = 0; axis < 3; ++axis) {
    g.lo[axis] = int(std::ceil(std::min({a[axis], b[axis], c[axis]}) - band));
    g.hi[axis] = int(std::floor(std::max({a[axis], b[axis], c[axis]}) + band));
  }
  return g;
}

std::uint64_t leafKey(const openvdb::Coord& leaf) {
  return (std::uint64_t(leaf.x() + kKeyOffset) << 42) |
         (std::uint64_t(leaf.y() + kKeyOffset) << 21) | std::uint64_t(leaf.z() + kKeyOffset);
}

openvdb::Coord leafOrigin(std::uint64_t key) {
  const auto axis = [&](int shift) {
    return int((std::int64_t((key >> shift) & ((1u << 21) - 1)) - kKeyOffset) << kLeafLog2);
  };
  return {axis(42), axis(21), axis(0)};
}

struct LeafTriangle {
  std::uint64_t leaf;
  std::uint32_t triangle;
  bool operator<(const LeafTriangle& other) const {
    return std::tie(leaf, triangle) < std::tie(other.leaf, other.triangle);
  }
};

/// The nearest triangle of every voxel of one 8³ leaf, by brute force over the triangles whose
/// band reaches the leaf; a plane-distance and a bounding-sphere bound skip most of them.
struct NearestInLeaf {
  openvdb::Coord origin;
  float band = 0;
  float best[FloatLeaf::SIZE];          ///< squared distance to the nearest triangle so far
  float bestDistance[FloatLeaf::SIZE];  ///< its square root
  std::int32_t nearest[FloatLeaf::SIZE];

  void reset(const openvdb::Coord& leafOrigin, float bandWidth) {
    origin = leafOrigin;
    band = bandWidth;
    std::fill(std::begin(best), std::end(best), band * band);
    std::fill(std::begin(bestDistance), std::end(bestDistance), band);
    std::fill(std::begin(nearest), std::end(nearest), -1);
  }

  void consider(std::uint32_t t, const TriangleGeometry& g) {
    const openvdb::Coord lo = openvdb::Coord::maxComponent(g.lo, origin);
    const openvdb::Coord hi = openvdb::Coord::minComponent(g.hi, origin.offsetBy(kLeafMask));
    for (int x = lo.x(); x <= hi.x(); ++x) {
      for (int y = lo.y(); y <= hi.y(); ++y) {
        // Only the run of the column inside the slab |plane distance| < band can be near.
        int zLo = lo.z(), zHi = hi.z();
        const float base = g.normal.x() * (float(x) - g.a.x()) +
                           g.normal.y() * (float(y) - g.a.y()) - g.normal.z() * g.a.z();
        if (std::abs(g.normal.z()) > 1e-6f) {
          float z0 = (-band - base) / g.normal.z(), z1 = (band - base) / g.normal.z();
          if (z0 > z1) std::swap(z0, z1);
          zLo = std::max(zLo, int(std::ceil(z0)));
          zHi = std::min(zHi, int(std::floor(z1)));
        } else if (std::abs(base) >= band) {
          continue;
        }
        for (int z = zLo; z <= zHi; ++z) {
          const Vec3s p{float(x), float(y), float(z)};
          const int offset = ((x & kLeafMask) << 6) | ((y & kLeafMask) << 3) | (z & kLeafMask);
          const float plane = g.normal.dot(p - g.a);
          if (plane * plane >= best[offset]) continue;
          // Neighbours on a smooth surface are nearly coplanar, so the plane rarely rejects
          // them; their distance from the voxel's side does, through the bounding sphere.
          const float near = g.radius + bestDistance[offset];
          if ((p - g.centre).lengthSqr() >= near * near) continue;
          const NearestPoint q = nearestOnTriangle(p, g.a, g.b, g.c);
          const float squared = (p - (q.u * g.a + q.v * g.b + q.w * g.c)).lengthSqr();
          if (squared < best[offset]) {
            best[offset] = squared;
            bestDistance[offset] = std::sqrt(squared);
            nearest[offset] = std::int32_t(t);
          }
        }
      }
    }
  }
};

/// Angle between the edges leaving corner `a`, robust near 0 and π.
float cornerAngle(const Vec3s& a, const Vec3s& b, const Vec3s& c) {
  const Vec3s ab = b - a, ac = c - a;
  return std::atan2(ab.cross(ac).length(), ab.dot(ac));
}

}  // namespace

MeshLevelSet::MeshLevelSet(std::vector<TriangleIndices> triangles, std::size_t vertexCount,
                           bool closed)
    : triangles_(std::move(triangles)), vertexCount_(vertexCount), closed_(closed) {
  for (const TriangleIndices& t : triangles_)
    for (std::uint32_t v : t)
      if (v >= vertexCount_)
        throw Error(cat("triangle vertex ", v, " is beyond the ", vertexCount_, " vertices"));
  if (!closed_) return;

  // Undirected edges: sort every (low, high, corner) use, equal (low, high) runs are one edge.
  const std::size_t corners = 3 * triangles_.size();
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> uses(corners);
  for (std::size_t t = 0; t < triangles_.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t p = triangles_[t][e], q = triangles_[t][(e + 1) % 3];
      uses[3 * t + e] = {std::min(p, q), std::max(p, q), std::uint32_t(3 * t + e)};
    }
  std::sort(uses.begin(), uses.end());
  edgeOfCorner_.resize(corners);
  edgeTriangles_.resize(corners);
  for (std::size_t i = 0; i < corners; ++i) {
    const bool newEdge = i == 0 || std::get<0>(uses[i]) != std::get<0>(uses[i - 1]) ||
                         std::get<1>(uses[i]) != std::get<1>(uses[i - 1]);
    if (newEdge) edgeStart_.push_back(std::uint32_t(i));
    edgeOfCorner_[std::get<2>(uses[i])] = std::uint32_t(edgeStart_.size() - 1);
    edgeTriangles_[i] = std::get<2>(uses[i]) / 3;
  }
  edgeStart_.push_back(std::uint32_t(corners));

  vertexStart_.assign(vertexCount_ + 1, 0);
  for (const TriangleIndices& t : triangles_)
    for (std::uint32_t v : t) ++vertexStart_[v + 1];
  for (std::size_t v = 0; v < vertexCount_; ++v) vertexStart_[v + 1] += vertexStart_[v];
  vertexCorners_.resize(corners);
  std::vector<std::uint32_t> fill(vertexStart_.begin(), vertexStart_.end() - 1);
  for (std::size_t t = 0; t < triangles_.size(); ++t)
    for (int k = 0; k < 3; ++k) vertexCorners_[fill[triangles_[t][k]]++] = std::uint32_t(3 * t + k);
}

MeshLevelSet::Grids MeshLevelSet::build(const std::vector<openvdb::Vec3s>& points,
                                        const openvdb::Vec3s* velocities, float band,
                                        double voxelSize) const {
  if (points.size() != vertexCount_)
    throw Error(cat("level set of ", vertexCount_, " vertices given ", points.size(), " points"));
  if (!(band >= 1)) throw Error(cat("level-set band of ", band, " voxels is below 1"));
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int axis = 0; axis < 3; ++axis)
      if (!(std::abs(points[i][axis]) <= kMaxCoordinate))
        throw Error(cat("vertex ", i, " lies ", points[i][axis],
                        " voxels from the origin, beyond the ", kMaxCoordinate,
                        " a level set can index: use a larger voxel size"));

  const std::size_t triangleCount = triangles_.size();
  const float background = float(band * voxelSize);

  // Per triangle: corners, unit normal, bounding sphere and the voxels its band can reach.
  std::vector<TriangleGeometry> geometry(triangleCount);
  std::vector<std::size_t> leafCount(triangleCount + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangleCount, 1024), [&](const auto& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const TriangleIndices& corners = triangles_[t];
      geometry[t] =
          triangleGeometry(points[corners[0]], points[corners[1]], points[corners[2]], band);
      leafCount[t + 1] = geometry[t].leafCount();
    }
  });
  for (std::size_t t = 0; t < triangleCount; ++t) leafCount[t + 1] += leafCount[t];

  // Every (leaf, triangle) pair whose band meets, sorted by leaf: each leaf is then one task
  // that owns its voxels, and the fixed order makes ties resolve the same on any thread count.
  std::vector<LeafTriangle> pairs(leafCount[triangleCount]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangleCount, 1024), [&](const auto& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const TriangleGeometry& g = geometry[t];
      std::size_t out = leafCount[t];
      for (int x = g.lo.x() >> kLeafLog2; x <= g.hi.x() >> kLeafLog2; ++x)
        for (int y = g.lo.y() >> kLeafLog2; y <= g.hi.y() >> kLeafLog2; ++y)
          for (int z = g.lo.z() >> kLeafLog2; z <= g.hi.z() >> kLeafLog2; ++z)
            pairs[out++] = {leafKey({x, y, z}), std::uint32_t(t)};
    }
  });
  tbb::parallel_sort(pairs.begin(), pairs.end());
  std::vector<std::size_t> leafStart;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (i == 0 || pairs[i].leaf != pairs[i - 1].leaf) leafStart.push_back(i);
  leafStart.push_back(pairs.size());
  const std::size_t leafTotal = leafStart.size() - 1;

  // Pseudonormals of the faces, edges and vertices, for the sign.
  std::vector<Vec3s> edgeNormal, vertexNormal;
  if (closed_) {
    edgeNormal.resize(edgeStart_.size() - 1);
    vertexNormal.resize(vertexCount_);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edgeNormal.size(), 4096), [&](auto r) {
      for (std::size_t e = r.begin(); e != r.end(); ++e) {
        Vec3s sum(0.0f);
        for (std::uint32_t i = edgeStart_[e]; i < edgeStart_[e + 1]; ++i)
          sum += geometry[edgeTriangles_[i]].normal;
        edgeNormal[e] = sum;
      }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertexCount_, 4096), [&](auto r) {
      for (std::size_t v = r.begin(); v != r.end(); ++v) {
        Vec3s sum(0.0f);
        for (std::uint32_t i = vertexStart_[v]; i < vertexStart_[v + 1]; ++i) {
          const TriangleGeometry& g = geometry[vertexCorners_[i] / 3];
          const int k = int(vertexCorners_[i] % 3);
          const float angle = k == 0   ? cornerAngle(g.a, g.b, g.c)
                              : k == 1 ? cornerAngle(g.b, g.c, g.a)
                                       : cornerAngle(g.c, g.a, g.b);
          sum += angle * g.normal;
        }
        vertexNormal[v] = sum;
      }
    });
  }
  const auto pseudonormal = [&](std::uint32_t t, Feature feature) -> Vec3s {
    switch (feature) {
      case Feature::Face:
        return geometry[t].normal;
      case Feature::VertexA:
        return vertexNormal[triangles_[t][0]];
      case Feature::VertexB:
        return vertexNormal[triangles_[t][1]];
      case Feature::VertexC:
        return vertexNormal[triangles_[t][2]];
      case Feature::EdgeAB:
        return edgeNormal[edgeOfCorner_[3 * t + 0]];
      case Feature::EdgeBC:
        return edgeNormal[edgeOfCorner_[3 * t + 1]];
      case Feature::EdgeCA:
        return edgeNormal[edgeOfCorner_[3 * t + 2]];
    }
    return geometry[t].normal;
  };

  // Each leaf: the nearest triangle of every voxel by brute force over the leaf's triangles
  // (the plane distance, a lower bound, skips most), then distance, sign and velocity.
  std::vector<FloatLeaf*> distanceLeaves(leafTotal, nullptr);
  std::vector<VelocityLeaf*> velocityLeaves(leafTotal, nullptr);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leafTotal, 4), [&](const auto& r) {
    NearestInLeaf nearer;
    for (std::size_t leaf = r.begin(); leaf != r.end(); ++leaf) {
      const openvdb::Coord origin = leafOrigin(pairs[leafStart[leaf]].leaf);
      nearer.reset(origin, band);
      for (std::size_t i = leafStart[leaf]; i < leafStart[leaf + 1]; ++i)
        nearer.consider(pairs[i].triangle, geometry[pairs[i].triangle]);
      auto distance = std::make_unique<FloatLeaf>(origin, background, false);
      std::unique_ptr<VelocityLeaf> velocity;
      if (velocities) velocity = std::make_unique<VelocityLeaf>(origin, Vec3s(0.0f), false);
      bool any = false;
      for (openvdb::Index offset = 0; offset < FloatLeaf::SIZE; ++offset) {
        if (nearer.nearest[offset] < 0) continue;
        const std::uint32_t t = std::uint32_t(nearer.nearest[offset]);
        const TriangleGeometry& g = geometry[t];
        const Vec3s p = FloatLeaf::offsetToLocalCoord(offset)
                            .offsetBy(origin.x(), origin.y(), origin.z())
                            .asVec3s();
        const NearestPoint q = nearestOnTriangle(p, g.a, g.b, g.c);
        const Vec3s away = p - (q.u * g.a + q.v * g.b + q.w * g.c);
        float value = std::sqrt(nearer.best[offset]);
        if (closed_ && away.dot(pseudonormal(t, q.feature)) < 0) value = -value;
        distance->setValueOn(offset, float(value * voxelSize));
        if (velocity) {
          const TriangleIndices& corners = triangles_[t];
          velocity->setValueOn(offset, q.u * velocities[corners[0]] + q.v * velocities[corners[1]] +
                                           q.w * velocities[corners[2]]);
        }
        any = true;
      }
      if (!any) continue;
      distanceLeaves[leaf] = distance.release();
      if (velocity) velocityLeaves[leaf] = velocity.release();
    }
  });

  auto distanceTree = std::make_shared<openvdb::FloatTree>(background);
  for (FloatLeaf* leaf : distanceLeaves)
    if (leaf) distanceTree->addLeaf(leaf);
  // Inactive voxels and tiles inside the body take −background, from the band's signs.
  if (closed_) openvdb::tools::signedFloodFillWithValues(*distanceTree, background, -background);

  const openvdb::math::Transform::Ptr transform =
      openvdb::math::Transform::createLinearTransform(voxelSize);
  Grids grids;
  grids.distance = openvdb::FloatGrid::create(distanceTree);
  grids.distance->setTransform(transform);
  grids.distance->setGridClass(closed_ ? openvdb::GRID_LEVEL_SET : openvdb::GRID_UNKNOWN);
  if (velocities) {
    auto velocityTree = std::make_shared<openvdb::Vec3STree>(Vec3s(0.0f));
    for (VelocityLeaf* leaf : velocityLeaves)
      if (leaf) velocityTree->addLeaf(leaf);
    grids.velocity = openvdb::Vec3SGrid::create(velocityTree);
    grids.velocity->setTransform(transform);
  }
  return grids;
}

}  // namespace softbake
