#pragma once
/// A body's UVs the way an OBJ file indexes them.
///
/// A render vertex exists per distinct (position, UV, normal) of the source, and assimp's OBJ
/// reader even makes one per face corner, so writing one `vt` per render vertex repeats each UV
/// many times (spot.obj: 3 225 `vt` in, 17 568 out). The table holds each distinct UV once.

#include <vector>

#include "core/scene/scene_topology.hpp"

namespace softbake {

struct TexcoordTable {
  std::vector<Vec2f> uvs;         ///< each distinct UV once, in order of first use
  std::vector<Triangle> corners;  ///< per body triangle, 0-based indices into `uvs`
};

/// The table of `render`, whose renderTriangles must index its uvs (empty when it has none).
/// Equal values are one UV, so 0 and -0 are too.
TexcoordTable texcoordTable(const RenderMesh& render);

}  // namespace softbake
