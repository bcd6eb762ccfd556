#pragma once
/// Every triangle that takes part in collisions, soft and static, in one index space.
///
/// Collision surface s < bodies.size() is body s and its triangles are the body's triangles at
/// the same global indices; static mesh colliders follow, their vertices numbered after the
/// particles. So a collision triangle, a surface or a vertex is one integer everywhere in the
/// pipeline, and the broad phases need no notion of "soft" or "static".

#include <algorithm>
#include <span>
#include <utility>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/collision/self_patches.hpp"
#include "core/collision/triangle_pair_intersection.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/types.hpp"

namespace softbake {

struct SceneTopology;
struct SubstepMotion;

/// Whether `v` is one of the corners of `t`.
inline bool hasVertex(const Triangle& t, Index v) {
  return t[0] == v || t[1] == v || t[2] == v;
}

struct CollisionGeometry {
  std::vector<CollisionSurface> surfaces;
  std::vector<Triangle> triangleVertices;  ///< soft: particle indices; static: particleCount + i
  std::vector<Index> triangleSurface;
  std::vector<Vec3> staticVertex;             ///< static mesh vertices, world space
  std::vector<Scalar> restitution, friction;  ///< per surface
  std::vector<bool> surfaceClosed;            ///< per surface: has an inside (edge pushes use it)
  Index particleCount = 0;                    ///< first static vertex index
  Index softTriangleCount = 0;                ///< first static triangle index
  SelfPatches selfPatches;                    ///< the self-colliding surfaces cut into patches
  /// The triangles around each collision vertex: those of vertex v are
  /// vertexTriangles[vertexTriangleStart[v] .. vertexTriangleStart[v + 1]), all on v's surface
  /// (linkVertexTriangles; empty until then).
  std::vector<Index> vertexTriangleStart, vertexTriangles;

  /// The position of collision vertex `v`: particle v of `positions`, or a static mesh vertex.
  const Vec3& vertex(std::span<const Vec3> positions, Index v) const {
    return v < particleCount ? positions[v] : staticVertex[v - particleCount];
  }
  /// The corners of collision triangle `triangle`, its particles taken from `positions`.
  TriangleCorners corners(std::span<const Vec3> positions, Index triangle) const {
    const Triangle& t = triangleVertices[triangle];
    return {vertex(positions, t[0]), vertex(positions, t[1]), vertex(positions, t[2])};
  }
  /// Whether collision triangles t and u cross at `positions` (intersectTrianglePair). Two that
  /// share a vertex touch there by construction: that is the mesh, not a crossing.
  bool trianglesCross(std::span<const Vec3> positions, Index t, Index u,
                      TrianglePairHits& hits) const {
    if (shareVertex(t, u)) return false;
    return intersectTrianglePair(corners(positions, t), corners(positions, u), hits);
  }
  /// The triangles that have `v` as a corner (linkVertexTriangles must have run).
  std::span<const Index> trianglesAround(Index v) const {
    return std::span(vertexTriangles)
        .subspan(vertexTriangleStart[v], vertexTriangleStart[v + 1] - vertexTriangleStart[v]);
  }
  /// Whether collision triangles t and u have a vertex in common.
  bool shareVertex(Index t, Index u) const {
    for (Index v : triangleVertices[u])
      if (hasVertex(triangleVertices[t], v)) return true;
    return false;
  }
  /// What a broad phase reads, with this substep's `triangleBox` (one per collision triangle) and,
  /// for normal-cone culling, which patches are flat (updateFlatPatches; none culls nothing).
  BroadPhaseInput broadPhaseInput(std::span<const Box3> triangleBox,
                                  const PatchFlatness* flatness = nullptr) const {
    BroadPhaseInput input{.triangleBox = triangleBox,
                          .triangleVertices = triangleVertices,
                          .triangleSurface = triangleSurface,
                          .surfaces = surfaces,
                          .trianglePatch = selfPatches.trianglePatch};
    if (flatness) {
      input.patchFlat = flatness->flat;
      input.patchNeighbourStart = selfPatches.neighbourStart;
      input.patchNeighbour = selfPatches.neighbours;
      input.patchFlatWith = flatness->flatWith;
    }
    return input;
  }
};

/// Whether surfaces `a` and `b`, in either order, are a pair of `surfacePairs` (sorted, lower
/// surface first).
inline bool holdsSurfacePair(std::span<const std::pair<Index, Index>> surfacePairs, Index a,
                             Index b) {
  return !surfacePairs.empty() && std::binary_search(surfacePairs.begin(), surfacePairs.end(),
                                                     std::pair(std::min(a, b), std::max(a, b)));
}

/// Removes from `pairs` the triangle pairs between the surfaces of `surfacePairs` (sorted, lower
/// surface first; a surface with itself for pairs within one).
void dropSurfacePairs(const CollisionGeometry& geometry,
                      std::span<const std::pair<Index, Index>> surfacePairs,
                      std::vector<TrianglePair>& pairs);

/// Fills `vertexTriangleStart` and `vertexTriangles` from the triangles.
void linkVertexTriangles(CollisionGeometry& geometry);

/// The collision geometry of the topology's bodies and static shapes (welded by
/// buildSceneTopology(), so triangles that touch share vertices). Built by the Simulator, which
/// holds it for its collision stages.
CollisionGeometry buildCollisionGeometry(const SceneTopology& topology);

/// Refreshes `boxes`, one per collision triangle: each soft triangle's box covers its corners at
/// the start and the end of the substep, so it holds every particle's segment of the step,
/// inflated by the skin so resting contacts stay candidates. Static triangles' boxes are computed
/// when `boxes` does not have the right size yet, and kept after that.
void updateCollisionBoxes(const SceneTopology& topology, const CollisionGeometry& geometry,
                          const SubstepMotion& motion, std::vector<Box3>& boxes);
/// The same, inflated by `margin` instead of the skin (a box is grown by a margin only once: the
/// static triangles' boxes keep the margin of the first call).
void updateCollisionBoxes(const SceneTopology& topology, const CollisionGeometry& geometry,
                          const SubstepMotion& motion, std::vector<Box3>& boxes, Scalar margin);
/// The same, through `particleBoxes`, which receives each particle's box over its segment of the
/// substep, inflated by `margin`: a soft triangle's box is the union of its corners' (the same box
/// to the bit, as rounding is monotonic, so inflating commutes with min and max), and each
/// position is read once instead of once per triangle around it. The per-step callers keep
/// `particleBoxes`, so no step allocates.
void updateCollisionBoxes(const SceneTopology& topology, const CollisionGeometry& geometry,
                          const SubstepMotion& motion, std::vector<Box3>& boxes, Scalar margin,
                          std::vector<Box3>& particleBoxes);

}  // namespace softbake
