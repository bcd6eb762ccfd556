#include "core/collision/self_patches.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <span>
#include <utility>

#include "core/collision/geometry.hpp"

namespace softbake {

namespace {
constexpr std::size_t kPatchGrain = 8;   ///< patches per chunk of the cone test, at least
constexpr Index kPatchTriangles = 32;    ///< most triangles of a patch
constexpr double kFlatConeAngle = 80.0;  ///< degrees from the patch's mean normal
/// How close two triangles seen along an axis may come, against the longer edge of the two,
/// before they count as lying over each other: unwelded seams of a CAD part (a cap's rim and its
/// wall's foot, 1.6 µm apart) touch there and cross at the slightest turn. Two triangles of a
/// welded disc that share no vertex keep a triangle's height between them, a tenth of an edge at
/// the cone's steepest.
constexpr double kNearOfEdge = 1e-2;

/// A triangle projected into a plane: its corners, its box and its longest edge.
struct Seen {
  std::array<Eigen::Vector2d, 3> corner;
  Eigen::AlignedBox2d box;
  double longest = 0;
};

/// Whether two triangles, projected into one plane, overlap there or come within `margin`: no
/// separating axis (the six edge normals) keeps them further apart. Conservative: corners that
/// face each other may be further apart than any of these tells.
bool nearInPlane(const Seen& a, const Seen& b, double margin) {
  for (const Seen* t : {&a, &b})
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d edge = t->corner[(k + 1) % 3] - t->corner[k];
      const double length = edge.norm();
      if (!(length > 0)) continue;
      const Eigen::Vector2d normal(-edge.y() / length, edge.x() / length);
      const auto extent = [&](const Seen& seen) {
        const double d0 = normal.dot(seen.corner[0]), d1 = normal.dot(seen.corner[1]),
                     d2 = normal.dot(seen.corner[2]);
        return std::pair(std::min({d0, d1, d2}), std::max({d0, d1, d2}));
      };
      const auto [aLow, aHigh] = extent(a);
      const auto [bLow, bHigh] = extent(b);
      if (bLow - aHigh > margin || aLow - bHigh > margin) return false;
    }
  return true;
}

/// Whether the rest shape of the triangles `first` (with `second`, when given: then only the
/// pairs across the two) lies over itself along the axis of its rest normals: two triangles that
/// share no vertex overlap, or nearly, seen along it.
bool liesOverItself(const CollisionGeometry& geometry, std::span<const Vec3> rest,
                    std::span<const Index> first, std::span<const Index> second) {
  const auto corner = [&](Index t, int k) {
    return rest[geometry.triangleVertices[t][k]].cast<double>();
  };
  Vec3d axis = Vec3d::Zero();
  for (std::span<const Index> part : {first, second})
    for (Index t : part) axis += (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0));
  if (!(axis.squaredNorm() > 0)) return true;
  axis.normalize();
  const Vec3d u = axis.unitOrthogonal(), v = axis.cross(u);
  // Each triangle projected once: a pair of patches is 32 × 32 pairs of them.
  std::array<Seen, 2 * kPatchTriangles> seen;
  const std::size_t count = first.size() + second.size();
  const auto triangle = [&](std::size_t i) {
    return i < first.size() ? first[i] : second[i - first.size()];
  };
  for (std::size_t i = 0; i < count; ++i) {
    Seen& out = seen[i];
    for (int k = 0; k < 3; ++k) {
      const Vec3d c = corner(triangle(i), k);
      out.corner[k] = {u.dot(c), v.dot(c)};
      out.box.extend(out.corner[k]);
    }
    for (int k = 0; k < 3; ++k)
      out.longest = std::max(out.longest, (out.corner[(k + 1) % 3] - out.corner[k]).norm());
  }
  const auto shareVertex = [&](Index a, Index b) {
    for (Index x : geometry.triangleVertices[a])
      for (Index y : geometry.triangleVertices[b])
        if (x == y) return true;
    return false;
  };
  // The boxes first: most pairs of two patches are far apart, and their test is the cheapest.
  const auto boxesNear = [](const Seen& a, const Seen& b, double margin) {
    for (int d = 0; d < 2; ++d)
      if (b.box.min()[d] - a.box.max()[d] > margin || a.box.min()[d] - b.box.max()[d] > margin)
        return false;
    return true;
  };
  for (std::size_t i = 0; i < first.size(); ++i)
    for (std::size_t j = second.empty() ? i + 1 : first.size(); j < count; ++j) {
      const double margin = kNearOfEdge * std::max(seen[i].longest, seen[j].longest);
      if (margin > 0 && boxesNear(seen[i], seen[j], margin) &&
          !shareVertex(triangle(i), triangle(j)) && nearInPlane(seen[i], seen[j], margin))
        return true;
    }
  return false;
}
}  // namespace

SelfPatches buildSelfPatches(const CollisionGeometry& geometry, std::span<const Vec3> rest) {
  SelfPatches patches;
  patches.trianglePatch.assign(geometry.triangleVertices.size(), kNoPatch);
  patches.patchStart.push_back(0);
  // Triangles across each edge, from one sorted list of (edge, triangle): linear after the sort.
  std::vector<std::pair<std::uint64_t, Index>> edges;
  std::vector<Index> queue;
  for (const CollisionSurface& surface : geometry.surfaces) {
    if (!surface.moving || !surface.selfCollision) continue;
    const Index first = surface.firstTriangle, end = first + surface.triangleCount;
    edges.clear();
    for (Index t = first; t < end; ++t) {
      const Triangle& v = geometry.triangleVertices[t];
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t a = v[k], b = v[(k + 1) % 3];
        edges.emplace_back(std::min(a, b) << 32 | std::max(a, b), t);
      }
    }
    std::sort(edges.begin(), edges.end());
    // neighbours[3·(t − first) + k]: the triangles across t's edges (kNoPatch where none, or
    // where more than two meet: a non-manifold edge joins nothing).
    std::vector<Index> neighbours(3 * std::size_t(surface.triangleCount), kNoPatch);
    std::vector<std::uint8_t> filled(surface.triangleCount, 0);
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j].first == edges[i].first) ++j;
      if (j - i == 2) {
        const Index a = edges[i].second, b = edges[i + 1].second;
        if (a != b) {
          neighbours[3 * (a - first) + filled[a - first]++] = b;
          neighbours[3 * (b - first) + filled[b - first]++] = a;
        }
      }
      i = j;
    }
    for (Index seed = first; seed < end; ++seed) {
      if (patches.trianglePatch[seed] != kNoPatch) continue;
      const Index patch = Index(patches.patchCount());
      queue.assign(1, seed);
      patches.trianglePatch[seed] = patch;
      for (std::size_t head = 0; head < queue.size() && queue.size() < kPatchTriangles; ++head)
        for (int k = 0; k < 3 && queue.size() < kPatchTriangles; ++k) {
          const Index n = neighbours[3 * (queue[head] - first) + k];
          if (n == kNoPatch || patches.trianglePatch[n] != kNoPatch) continue;
          patches.trianglePatch[n] = patch;
          queue.push_back(n);
        }
      patches.triangles.insert(patches.triangles.end(), queue.begin(), queue.end());
      patches.patchStart.push_back(Index(patches.triangles.size()));
    }
  }
  // Neighbouring patches: those that meet at a vertex, from one sorted list of (vertex, patch).
  std::vector<std::pair<Index, Index>> corners, adjacent;
  for (Index t = 0; t < patches.trianglePatch.size(); ++t)
    if (const Index patch = patches.trianglePatch[t]; patch != kNoPatch)
      for (Index v : geometry.triangleVertices[t]) corners.emplace_back(v, patch);
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  for (std::size_t i = 0; i < corners.size();) {
    std::size_t j = i;
    while (j < corners.size() && corners[j].first == corners[i].first) ++j;
    for (std::size_t a = i; a < j; ++a)
      for (std::size_t b = i; b < j; ++b)
        if (a != b) adjacent.emplace_back(corners[a].second, corners[b].second);
    i = j;
  }
  std::sort(adjacent.begin(), adjacent.end());
  adjacent.erase(std::unique(adjacent.begin(), adjacent.end()), adjacent.end());
  patches.neighbourStart.assign(patches.patchCount() + 1, 0);
  for (const auto& [patch, other] : adjacent) {
    ++patches.neighbourStart[patch + 1];
    patches.neighbours.push_back(other);
  }
  for (std::size_t p = 0; p < patches.patchCount(); ++p)
    patches.neighbourStart[p + 1] += patches.neighbourStart[p];
  // Each pair of neighbours from its lower patch, written to both entries: one verdict for both.
  patches.overlapsAtRest.assign(patches.patchCount(), 0);
  patches.overlapsAtRestWith.assign(patches.neighbours.size(), 0);
  const auto trianglesOf = [&](Index p) {
    return std::span<const Index>(patches.triangles)
        .subspan(patches.patchStart[p], patches.patchStart[p + 1] - patches.patchStart[p]);
  };
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, patches.patchCount(), kPatchGrain),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t p = range.begin(); p != range.end(); ++p) {
          patches.overlapsAtRest[p] = liesOverItself(geometry, rest, trianglesOf(Index(p)), {});
          for (Index k = patches.neighbourStart[p]; k < patches.neighbourStart[p + 1]; ++k) {
            const Index q = patches.neighbours[k];
            if (q < p) continue;
            const std::uint8_t over =
                liesOverItself(geometry, rest, trianglesOf(Index(p)), trianglesOf(q));
            patches.overlapsAtRestWith[k] = over;
            const auto from = patches.neighbours.begin() + patches.neighbourStart[q];
            const auto to = patches.neighbours.begin() + patches.neighbourStart[q + 1];
            patches.overlapsAtRestWith[std::lower_bound(from, to, Index(p)) -
                                       patches.neighbours.begin()] = over;
          }
        }
      });
  return patches;
}

void updateFlatPatches(const CollisionGeometry& geometry, std::span<const Vec3> start,
                       std::span<const Vec3> end, PatchFlatness& out) {
  const SelfPatches& patches = geometry.selfPatches;
  const std::size_t count = patches.patchCount();
  out.flat.resize(count);
  out.axis.resize(count);
  out.halfAngle.resize(count);
  out.flatWith.resize(patches.neighbours.size());
  const double limit = kFlatConeAngle * std::numbers::pi / 180.0;
  // n within the cone of half-angle θ around a: n·a > cos θ·|n|·|a|, squared to spare the roots.
  const double cosine = std::cos(limit);
  const Scalar cosineSquared = Scalar(cosine * cosine);
  // Patches cover soft triangles only, whose corners are particles.
  const Triangle* vertices = geometry.triangleVertices.data();
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, count, kPatchGrain),
      [&](const tbb::blocked_range<std::size_t>& range) {
        std::array<Vec3, 2 * kPatchTriangles> normals;
        for (std::size_t p = range.begin(); p != range.end(); ++p) {
          const Index first = patches.patchStart[p], size = patches.patchStart[p + 1] - first;
          Vec3 axis = Vec3::Zero();
          for (Index k = 0; k < size; ++k) {
            const Triangle& t = vertices[patches.triangles[first + k]];
            normals[2 * k] = (start[t[1]] - start[t[0]]).cross(start[t[2]] - start[t[0]]);
            normals[2 * k + 1] = (end[t[1]] - end[t[0]]).cross(end[t[2]] - end[t[0]]);
            axis += normals[2 * k] + normals[2 * k + 1];
          }
          const Scalar axisSquared = axis.squaredNorm();
          // A degenerate triangle has no direction: it cannot vouch for its patch.
          bool inCone = axisSquared > 0 && std::isfinite(axisSquared);
          double widest = 1;  // the least cosine of a normal to the axis
          for (Index k = 0; k < 2 * size && inCone; ++k) {
            const Scalar along = normals[k].dot(axis);
            inCone =
                along > 0 && along * along > cosineSquared * normals[k].squaredNorm() * axisSquared;
            widest = std::min(widest, double(along) / std::sqrt(double(normals[k].squaredNorm()) *
                                                                double(axisSquared)));
          }
          out.flat[p] = std::uint8_t(inCone && !patches.overlapsAtRest[p]);
          out.axis[p] = inCone ? Vec3d(axis.cast<double>().normalized()) : Vec3d::Zero();
          out.halfAngle[p] = inCone ? std::acos(std::clamp(widest, -1.0, 1.0)) : std::numbers::pi;
        }
      });
  // Each entry from its own patch's side; the merged cone is symmetric in the two, so both
  // entries of a pair agree.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, count, kPatchGrain),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t p = range.begin(); p != range.end(); ++p)
          for (Index k = patches.neighbourStart[p]; k < patches.neighbourStart[p + 1]; ++k) {
            const Index q = patches.neighbours[k];
            if (!out.flat[p] || !out.flat[q]) {
              out.flatWith[k] = 0;
              continue;
            }
            const double apart = std::acos(std::clamp(out.axis[p].dot(out.axis[q]), -1.0, 1.0));
            const double narrow = std::min(out.halfAngle[p], out.halfAngle[q]);
            const double wide = std::max(out.halfAngle[p], out.halfAngle[q]);
            const double merged = apart + narrow <= wide ? wide : (apart + narrow + wide) / 2;
            out.flatWith[k] = std::uint8_t(merged < limit && !patches.overlapsAtRestWith[k]);
          }
      });
}

}  // namespace softbake
