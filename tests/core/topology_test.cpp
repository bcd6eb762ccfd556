#include "core/mesh_topology.hpp"

#include <gtest/gtest.h>

#include "core/icosphere.hpp"

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
