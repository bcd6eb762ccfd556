#include "core/mesh/weld.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/Geometry>

namespace softbake {

namespace {

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};

struct CellKeyHash {
  std::size_t operator()(const CellKey& k) const {
    // Unsigned, where wrapping is defined: a cell far out has a large number (found by fuzzing:
    // the signed products overflowed). The same hash values as before wherever they did not.
    return std::size_t(k.x) * 73856093u ^ std::size_t(k.y) * 19349663u ^
           std::size_t(k.z) * 83492791u;
  }
};

struct TriangleKeyHash {
  std::size_t operator()(const Triangle& t) const {
    return std::size_t(t[0]) * 2654435761u ^ std::size_t(t[1]) * 40503u ^ std::size_t(t[2]);
  }
};

}  // namespace

WeldedMesh weldByPosition(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                          float relativeTolerance) {
  WeldedMesh out;
  out.renderToParticle.assign(positions.size(), kNoParticle);

  std::vector<char> referenced(positions.size(), 0);
  for (const Triangle& t : triangles)
    for (Index v : t) referenced[v] = 1;

  Eigen::AlignedBox3f bounds;
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (referenced[i]) bounds.extend(positions[i]);
  const float diagonal = bounds.isEmpty() ? 0.f : bounds.diagonal().norm();
  const float tolerance = std::max(diagonal * relativeTolerance, 1e-30f);

  // Cells of the tolerance's size: a vertex's twin lies in its own cell or one of the 26 around it.
  std::unordered_map<CellKey, std::vector<Index>, CellKeyHash> cells;
  // Clamped: a mesh far smaller than its distance from the origin gave cell numbers past int64,
  // undefined behaviour (found by fuzzing). Far cells then share one, which costs time, not
  // correctness, and the numbers of every other mesh are as before.
  auto cellIndex = [&](float coordinate) {
    return std::int64_t(std::clamp(std::floor(double(coordinate) / tolerance), -0x1p62, 0x1p62));
  };
  auto cellOf = [&](const Vec3f& p) {
    return CellKey{cellIndex(p.x()), cellIndex(p.y()), cellIndex(p.z())};
  };
  const float toleranceSquared = tolerance * tolerance;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!referenced[i]) {
      ++out.unreferencedVertices;
      continue;
    }
    const Vec3f& p = positions[i];
    const CellKey home = cellOf(p);
    Index match = kNoParticle;
    for (std::int64_t dx = -1; dx <= 1 && match == kNoParticle; ++dx)
      for (std::int64_t dy = -1; dy <= 1 && match == kNoParticle; ++dy)
        for (std::int64_t dz = -1; dz <= 1 && match == kNoParticle; ++dz) {
          auto it = cells.find({home.x + dx, home.y + dy, home.z + dz});
          if (it == cells.end()) continue;
          for (Index particle : it->second)
            if ((out.positions[particle] - p).squaredNorm() <= toleranceSquared) {
              match = particle;
              break;
            }
        }
    if (match == kNoParticle) {
      match = Index(out.positions.size());
      out.positions.push_back(p);
      cells[home].push_back(match);
    }
    out.renderToParticle[i] = match;
  }

  // A triangle thinner than this (area relative to the mesh's size) carries no usable normal.
  const float minDoubleArea = 1e-12f * diagonal * diagonal;
  std::unordered_set<Triangle, TriangleKeyHash> seen;
  out.triangles.reserve(triangles.size());
  out.renderTriangles.reserve(triangles.size());
  for (const Triangle& render : triangles) {
    const Triangle t = {out.renderToParticle[render[0]], out.renderToParticle[render[1]],
                        out.renderToParticle[render[2]]};
    const bool repeated = t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    if (repeated || (out.positions[t[1]] - out.positions[t[0]])
                            .cross(out.positions[t[2]] - out.positions[t[0]])
                            .norm() <= minDoubleArea) {
      ++out.degenerateTriangles;
      continue;
    }
    Triangle sorted = t;
    std::sort(sorted.begin(), sorted.end());
    if (!seen.insert(sorted).second) {
      ++out.duplicateTriangles;
      continue;
    }
    out.triangles.push_back(t);
    out.renderTriangles.push_back(render);
  }

  // Particles that only dropped triangles used would float free with no mass: remove them.
  std::vector<Index> remap(out.positions.size(), kNoParticle);
  for (const Triangle& t : out.triangles)
    for (Index v : t) remap[v] = 0;
  Index kept = 0;
  for (Index i = 0; i < remap.size(); ++i)
    if (remap[i] == 0) {
      out.positions[kept] = out.positions[i];
      remap[i] = kept++;
    }
  out.positions.resize(kept);
  for (Triangle& t : out.triangles)
    for (Index& v : t) v = remap[v];
  for (Index& particle : out.renderToParticle)
    if (particle != kNoParticle) particle = remap[particle];
  return out;
}

}  // namespace softbake
