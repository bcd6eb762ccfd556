#pragma once
/// Moving a mesh into world space: shared by the node hierarchy of imported files and the
/// `transform` of scene files, so both treat normals and mirroring the same way.

#include <Eigen/Geometry>

#include "core/mesh/triangle_mesh.hpp"

namespace softbake {

/// Applies `transform` to positions, and its inverse-transpose to normals (renormalised, so
/// non-uniform scale keeps them perpendicular to the surface). A mirroring transform
/// (determinant < 0) would turn the mesh inside-out, so the triangles' winding is reversed to keep
/// them counter-clockwise from outside. A singular transform flattens the mesh; its normals are
/// then meaningless and are cleared.
void transformMesh(TriangleMesh& mesh, const Eigen::Affine3d& transform);

/// Scale, then rotate (degrees about X, then Y, then Z), then translate.
Eigen::Affine3d composeTransform(const Eigen::Vector3d& translate,
                                 const Eigen::Vector3d& rotateDegrees,
                                 const Eigen::Vector3d& scale);

}  // namespace softbake
