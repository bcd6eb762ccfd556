#include "core/mesh/mesh_topology.hpp"

#include <algorithm>

namespace softbake {

namespace {

struct HalfEdge {
  IndexPair key;    // (min, max) of the two ends
  Index triangle;
  Index opposite;   // the triangle's third vertex
  bool forward;     // true when the triangle walks key[0] -> key[1]
};

}  // namespace

MeshTopology buildTopology(std::span<const Triangle> triangles) {
  std::vector<HalfEdge> halfEdges;
  halfEdges.reserve(triangles.size() * 3);
  for (Index t = 0; t < triangles.size(); ++t)
    for (int corner = 0; corner < 3; ++corner) {
      const Index a = triangles[t][corner], b = triangles[t][(corner + 1) % 3];
      const Index c = triangles[t][(corner + 2) % 3];
      halfEdges.push_back({{std::min(a, b), std::max(a, b)}, t, c, a < b});
    }
  // Sorting (rather than hashing) makes the spring order independent of any hash seed.
  std::sort(halfEdges.begin(), halfEdges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
  });

  MeshTopology topology;
  std::vector<IndexPair> bends;
  for (std::size_t first = 0; first < halfEdges.size();) {
    std::size_t last = first;
    while (last < halfEdges.size() && halfEdges[last].key == halfEdges[first].key) ++last;
    const std::size_t count = last - first;
    topology.edges.push_back(halfEdges[first].key);
    if (count == 1) ++topology.boundaryEdges;
    if (count > 2) ++topology.nonManifoldEdges;
    if (count == 2 && halfEdges[first].forward == halfEdges[first + 1].forward)
      ++topology.inconsistentEdges;
    // Every pair of triangles around the edge gets a bending spring, so non-manifold fins bend too.
    for (std::size_t i = first; i < last; ++i)
      for (std::size_t j = i + 1; j < last; ++j) {
        const Index p = halfEdges[i].opposite, q = halfEdges[j].opposite;
        if (p != q) bends.push_back({std::min(p, q), std::max(p, q)});
      }
    first = last;
  }

  std::sort(bends.begin(), bends.end());
  bends.erase(std::unique(bends.begin(), bends.end()), bends.end());
  // A bend pair that is also an edge (a tetrahedron's opposite corners) would double that spring.
  for (const IndexPair& bend : bends)
    if (!std::binary_search(topology.edges.begin(), topology.edges.end(), bend))
      topology.bendPairs.push_back(bend);
  return topology;
}

double signedVolume(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
  double volume = 0;
  for (const Triangle& t : triangles) {
    const Vec3d a = positions[t[0]].cast<double>(), b = positions[t[1]].cast<double>(),
                c = positions[t[2]].cast<double>();
    volume += a.dot(b.cross(c));
  }
  return volume / 6.0;
}

}  // namespace softbake
