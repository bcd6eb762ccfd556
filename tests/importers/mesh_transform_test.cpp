// Positions, normals and winding under the transforms of node trees and scene files.

#include <gtest/gtest.h>

#include "core/mesh/icosphere.hpp"
#include "core/mesh/mesh_topology.hpp"
#include "importers/mesh_transform.hpp"

namespace softbake {
namespace {

TEST(MeshTransform, ComposesScaleThenRotateXYZThenTranslate) {
  const Eigen::Affine3d t = composeTransform({0, 5, 0}, {90, 0, 90}, {2, 1, 1});
  // (1,0,0): scaled to (2,0,0), kept by the X turn, turned by Z to (0,2,0), lifted by 5.
  EXPECT_TRUE((t * Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(0, 7, 0), 1e-12));
  // (0,1,0): X turns it to (0,0,1), which Z leaves alone. Z first would have given (-1,0,0).
  EXPECT_TRUE((t * Eigen::Vector3d(0, 1, 0)).isApprox(Eigen::Vector3d(0, 5, 1), 1e-12));
  EXPECT_TRUE((composeTransform({0, 0, 0}, {0, 90, 0}, {1, 1, 1}) * Eigen::Vector3d(0, 0, 1))
                  .isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
}

TEST(MeshTransform, MirroringKeepsTheMeshWoundOutward) {
  TriangleMesh ball = makeIcosphere(2, 1);
  const double before = signedVolume(ball.positions, ball.triangles);
  transformMesh(ball, composeTransform({0, 0, 0}, {0, 0, 0}, {-1, 2, 1}));
  EXPECT_NEAR(signedVolume(ball.positions, ball.triangles), 2 * before, 1e-4 * before);
}

TEST(MeshTransform, NormalsStayPerpendicularUnderNonUniformScale) {
  // A triangle in the plane x + z = 0, wound counter-clockwise about (-1,0,-1).
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {0, 1, 0}, {1, 0, -1}};
  const Vec3f normal = Vec3f(-1, 0, -1).normalized();
  mesh.normals = {normal, normal, normal};
  mesh.triangles = {{0, 1, 2}};
  transformMesh(mesh, composeTransform({1, 2, 3}, {0, 0, 0}, {3, 1, 1}));
  const Vec3f a = mesh.positions[1] - mesh.positions[0], b = mesh.positions[2] - mesh.positions[0];
  for (const Vec3f& n : mesh.normals) {
    EXPECT_NEAR(n.norm(), 1, 1e-6);
    EXPECT_NEAR(n.dot(a), 0, 1e-6);
    EXPECT_NEAR(n.dot(b), 0, 1e-6);
    EXPECT_GT(n.dot(a.cross(b)), 0);  // same side as the winding
  }
}

TEST(MeshTransform, FlatteningDropsNormals) {
  TriangleMesh ball = makeIcosphere(1, 1);
  ball.normals = ball.positions;
  Eigen::Affine3d flatten = Eigen::Affine3d::Identity();
  flatten.scale(Eigen::Vector3d(1, 0, 1));
  transformMesh(ball, flatten);
  EXPECT_TRUE(ball.normals.empty());
  for (const Vec3f& p : ball.positions) EXPECT_EQ(p.y(), 0);
}

TEST(MeshTransform, SmallButRegularScalesKeepNormals) {
  TriangleMesh ball = makeIcosphere(1, 1);
  ball.normals = ball.positions;
  transformMesh(ball, composeTransform({0, 0, 0}, {0, 0, 0}, {0.01, 0.01, 0.01}));
  ASSERT_EQ(ball.normals.size(), ball.positions.size());
  for (std::size_t i = 0; i < ball.positions.size(); ++i)
    EXPECT_GT(ball.normals[i].dot(ball.positions[i].normalized()), 0.9999f);
}

}  // namespace
}  // namespace softbake
