#pragma once
/// Welding render vertices into simulation particles.
///
/// Files split a vertex wherever its UV or normal changes (and STL never shares vertices at all),
/// but a soft body needs one particle per point of the surface, or the seams tear open. Welding
/// merges render vertices whose positions coincide within a tolerance and keeps the map back, so
/// exporters can write the original UVs and normals for the deformed particles.

#include <span>
#include <vector>

#include "core/types.hpp"

namespace softbake {

inline constexpr Index kNoParticle = ~Index(0);

struct WeldedMesh {
  std::vector<Vec3f> positions;           ///< one per particle, in order of first appearance
  std::vector<Index> renderToParticle;    ///< per render vertex; kNoParticle when unreferenced
  std::vector<Triangle> triangles;        ///< particle indices of the triangles kept
  std::vector<Triangle> renderTriangles;  ///< the same triangles in render-vertex indices
  std::size_t degenerateTriangles = 0;    ///< dropped: repeated particle or zero area
  std::size_t duplicateTriangles = 0;     ///< dropped: same three particles as an earlier one
  std::size_t unreferencedVertices = 0;   ///< render vertices no triangle uses
};

/// Relative weld tolerance: positions closer than this times the mesh's bounding-box diagonal are
/// one particle. Far below any real feature size, far above float round-off of a transform.
inline constexpr float kWeldTolerance = 1e-6f;

/// Welds `positions` (render vertices) referenced by `triangles`. Deterministic: particle order is
/// the order of each particle's first render vertex.
WeldedMesh weldByPosition(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                          float relativeTolerance = kWeldTolerance);

}  // namespace softbake
