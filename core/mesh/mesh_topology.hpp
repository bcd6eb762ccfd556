#pragma once
/// Edges, bending pairs and closedness of a welded triangle mesh.

#include <span>
#include <vector>

#include "core/types.hpp"

namespace softbake {

using IndexPair = std::array<Index, 2>;

struct MeshTopology {
  std::vector<IndexPair> edges;  ///< every unique edge, first < second, sorted
  /// The two vertices opposite an edge shared by two triangles: a bending spring joins them.
  /// Pairs that coincide with an edge or with an earlier pair are left out.
  std::vector<IndexPair> bendPairs;
  std::size_t boundaryEdges = 0;     ///< edges with one triangle
  std::size_t nonManifoldEdges = 0;  ///< edges with more than two triangles
  std::size_t inconsistentEdges = 0; ///< two-triangle edges walked the same way by both
  /// Encloses a volume: every edge has two triangles that wind it in opposite directions.
  bool closed() const { return boundaryEdges == 0 && nonManifoldEdges == 0 && inconsistentEdges == 0; }
};

MeshTopology buildTopology(std::span<const Triangle> triangles);

/// Signed volume enclosed by a closed mesh (divergence theorem), accumulated in double.
double signedVolume(std::span<const Vec3f> positions, std::span<const Triangle> triangles);

}  // namespace softbake
