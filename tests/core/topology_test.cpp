#include "core/mesh/mesh_topology.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/mesh/cube_sphere.hpp"
#include "core/mesh/icosphere.hpp"

namespace softbake {
namespace {

TEST(Topology, IcosphereIsClosedWithEulerCharacteristicTwo) {
  for (int level = 0; level <= 3; ++level) {
    const TriangleMesh mesh = makeIcosphere(level, 1);
    const MeshTopology topology = buildTopology(mesh.triangles);
    EXPECT_TRUE(topology.closed());
    EXPECT_EQ(topology.edges.size() * 2, mesh.triangles.size() * 3);
    EXPECT_EQ(
        long(mesh.positions.size()) - long(topology.edges.size()) + long(mesh.triangles.size()), 2);
    // One bending spring per interior edge; none coincide with an edge on an icosphere.
    EXPECT_EQ(topology.bendPairs.size(), topology.edges.size());
    EXPECT_GT(signedVolume(mesh.positions, mesh.triangles), 0);
  }
}

TEST(Topology, CubeSphereIsClosedOutwardAndNearTheSphere) {
  for (int divisions : {1, 3, 9, 29}) {
    const TriangleMesh mesh = makeCubeSphere(divisions, 2.0f, Vec3f(1, -1, 0.5f));
    EXPECT_EQ(mesh.triangles.size(), std::size_t(12 * divisions * divisions));
    EXPECT_EQ(mesh.positions.size(), std::size_t(6 * divisions * divisions + 2));
    const MeshTopology topology = buildTopology(mesh.triangles);
    EXPECT_TRUE(topology.closed()) << divisions;
    for (const Vec3f& p : mesh.positions) EXPECT_NEAR((p - Vec3f(1, -1, 0.5f)).norm(), 2.0f, 1e-5f);
    const double volume = signedVolume(mesh.positions, mesh.triangles);
    const double sphere = 4.0 / 3.0 * std::numbers::pi * 8.0;
    EXPECT_GT(volume, 0);
    if (divisions == 1) {
      // The cube inscribed in the sphere: side 2·2/√3.
      EXPECT_NEAR(volume, std::pow(4 / std::sqrt(3.0), 3), 1e-5 * sphere);
      continue;
    }
    // Chords cut the sphere by O(h²): the deficit times divisions² is 1.012 at 3 divisions, 1.073
    // at 9 and 1.081 at 29.
    const double scaledDeficit = (sphere - volume) / sphere * divisions * divisions;
    RecordProperty("scaled_deficit_" + std::to_string(divisions), std::to_string(scaledDeficit));
    EXPECT_GT(scaledDeficit, 1.0) << divisions;
    EXPECT_LT(scaledDeficit, 1.1) << divisions;
  }
  EXPECT_EQ(cubeSphereDivisions(10000), 29);
  EXPECT_EQ(cubeSphereDivisions(1000000), 289);
  EXPECT_EQ(cubeSphereDivisions(0), 1);
}

TEST(Topology, RemovingATriangleOpensThreeBoundaryEdges) {
  TriangleMesh mesh = makeIcosphere(1, 1);
  mesh.triangles.pop_back();
  const MeshTopology topology = buildTopology(mesh.triangles);
  EXPECT_FALSE(topology.closed());
  EXPECT_EQ(topology.boundaryEdges, 3u);
}

TEST(Topology, FlippedTriangleMakesThreeInconsistentEdges) {
  TriangleMesh mesh = makeIcosphere(1, 1);
  std::swap(mesh.triangles[0][1], mesh.triangles[0][2]);
  const MeshTopology topology = buildTopology(mesh.triangles);
  EXPECT_FALSE(topology.closed());
  EXPECT_EQ(topology.inconsistentEdges, 3u);
}

TEST(Topology, TetrahedronBendPairsAreAllEdgesAlready) {
  const std::vector<Triangle> tetra = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  const MeshTopology topology = buildTopology(tetra);
  EXPECT_TRUE(topology.closed());
  EXPECT_EQ(topology.edges.size(), 6u);
  EXPECT_TRUE(topology.bendPairs.empty());
}

TEST(Topology, NonManifoldFinIsCountedAndBendsEveryPair) {
  // Three triangles sharing edge 0–1 (a fin), apexes 2, 3, 4.
  const std::vector<Triangle> fin = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshTopology topology = buildTopology(fin);
  EXPECT_EQ(topology.nonManifoldEdges, 1u);
  EXPECT_EQ(topology.bendPairs.size(), 3u);  // 2–3, 2–4, 3–4
}

}  // namespace
}  // namespace softbake
