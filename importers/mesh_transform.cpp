#include "importers/mesh_transform.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace softbake {

void transformMesh(TriangleMesh& mesh, const Eigen::Affine3d& transform) {
  if (transform.matrix() == Eigen::Matrix4d::Identity()) return;
  for (Vec3f& p : mesh.positions) p = (transform * p.cast<double>()).cast<float>();

  const Eigen::Matrix3d linear = transform.linear();
  const double determinant = linear.determinant();
  if (!mesh.normals.empty()) {
    // Relative to the transform's own size, so a ×0.01 node scale does not count as singular.
    const double size = std::max(linear.cwiseAbs().maxCoeff(), 1e-300);
    if (std::abs(determinant) <= 1e-12 * size * size * size) {
      mesh.normals.clear();
    } else {
      const Eigen::Matrix3d normalMatrix = linear.inverse().transpose();
      for (Vec3f& n : mesh.normals) {
        const Eigen::Vector3d m = normalMatrix * n.cast<double>();
        const double length = m.norm();
        // A zero normal in the file stays zero rather than becoming NaN.
        if (length > 0) n = (m / length).cast<float>();
      }
    }
  }
  if (determinant < 0)
    for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
}

Eigen::Affine3d composeTransform(const Eigen::Vector3d& translate,
                                 const Eigen::Vector3d& rotateDegrees,
                                 const Eigen::Vector3d& scale) {
  const Eigen::Vector3d radians = rotateDegrees * (std::numbers::pi / 180);
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();
  transform.translate(translate);
  // Rightmost acts first: X, then Y, then Z.
  transform.rotate(Eigen::AngleAxisd(radians.z(), Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(radians.y(), Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(radians.x(), Eigen::Vector3d::UnitX()));
  transform.scale(scale);
  return transform;
}

}  // namespace softbake
