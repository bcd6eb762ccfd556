#pragma once
/// Every triangle that takes part in collisions, soft and static, in one index space.
///
/// Collision surface s < bodies.size() is body s and its triangles are the body's triangles at
/// the same global indices; static mesh colliders follow, their vertices numbered after the
/// particles. So a collision triangle, a surface or a vertex is one integer everywhere in the
/// pipeline, and the broad phases need no notion of "soft" or "static".

#include <vector>

#include "core/collision/broad_phase.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/types.hpp"

namespace softbake {

struct World;

struct CollisionGeometry {
  std::vector<CollisionSurface> surfaces;
  std::vector<Triangle> triangleVertices;  ///< soft: particle indices; static: particleCount + i
  std::vector<Index> triangleSurface;
  std::vector<Box3> triangleBox;              ///< soft boxes are refreshed every substep
  std::vector<Vec3> staticVertex;             ///< static mesh vertices, world space
  std::vector<Scalar> restitution, friction;  ///< per surface
  std::vector<bool> surfaceClosed;            ///< per surface: has an inside (edge pushes use it)
  Index particleCount = 0;                    ///< first static vertex index
  Index softTriangleCount = 0;                ///< first static triangle index

  BroadPhaseInput broadPhaseInput() const {
    return {triangleBox, triangleVertices, triangleSurface, surfaces};
  }
};

/// Fills world.collision from the world's bodies and static mesh colliders (welded, so triangles
/// that touch share vertices). Called by buildWorld().
void buildCollisionGeometry(World& world);

/// Refreshes the soft triangles' boxes: each covers its corners at the start and the end of the
/// substep (previousPosition and position), so it holds every particle's segment of the step,
/// inflated by the skin so resting contacts stay candidates.
void updateCollisionBoxes(World& world);

}  // namespace softbake
