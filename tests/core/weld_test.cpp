#include "core/mesh/weld.hpp"

#include <gtest/gtest.h>

#include <random>

namespace softbake {
namespace {

/// A unit cube stored the way files store it: four vertices per face, 24 in all.
std::pair<std::vector<Vec3f>, std::vector<Triangle>> splitCube() {
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
  for (const auto& face : faces) {
    const Index base = Index(positions.size());
    for (int corner : face)
      positions.emplace_back(float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1));
    triangles.push_back({base, base + 1, base + 2});
    triangles.push_back({base, base + 2, base + 3});
  }
  return {positions, triangles};
}

TEST(Weld, SplitCubeBecomesEightParticles) {
  const auto [positions, triangles] = splitCube();
  const WeldedMesh welded = weldByPosition(positions, triangles);
  EXPECT_EQ(welded.positions.size(), 8u);
  EXPECT_EQ(welded.triangles.size(), 12u);
  for (std::size_t v = 0; v < positions.size(); ++v)
    EXPECT_EQ(welded.positions[welded.renderToParticle[v]], positions[v]);
  for (std::size_t t = 0; t < welded.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(welded.triangles[t][c], welded.renderToParticle[welded.renderTriangles[t][c]]);
}

TEST(Weld, DropsDegenerateDuplicateAndUnreferenced) {
  auto [positions, triangles] = splitCube();
  positions.emplace_back(5, 5, 5);         // unreferenced
  triangles.push_back({0, 1, 1});          // repeated vertex
  triangles.push_back({0, 5, 0});          // repeated vertex
  triangles.push_back(triangles[0]);       // duplicate
  positions.emplace_back(0.f, 0.5f, 0.f);  // on the edge 0–1: collinear
  triangles.push_back({0, 1, Index(positions.size() - 1)});
  const WeldedMesh welded = weldByPosition(positions, triangles);
  EXPECT_EQ(welded.triangles.size(), 12u);
  EXPECT_EQ(welded.degenerateTriangles, 3u);
  EXPECT_EQ(welded.duplicateTriangles, 1u);
  EXPECT_EQ(welded.unreferencedVertices, 1u);
  EXPECT_EQ(welded.positions.size(), 8u) << "the collinear triangle's extra vertex must go too";
  EXPECT_EQ(welded.renderToParticle[24], kNoParticle);
}

// Found by fuzzing: with every vertex in one place the tolerance falls to its floor (1e-30), and
// coordinates divided by it overflowed int64 in the cell numbers (undefined behaviour, which the
// sanitizer build reports). They weld to one particle and the triangle is degenerate.
TEST(Weld, VerticesAllInOnePlaceAwayFromTheOriginWeldToOneParticle) {
  const std::vector<Vec3f> positions(3, Vec3f(-3.1e-9f, 5, 1e20f));
  const std::vector<Triangle> triangles = {{0, 1, 2}};
  const WeldedMesh welded = weldByPosition(positions, triangles);
  EXPECT_EQ(welded.positions.size(), 0u);  // no triangle is left to use it
  EXPECT_EQ(welded.degenerateTriangles, 1u);
  EXPECT_EQ(welded.renderToParticle, std::vector<Index>(3, kNoParticle));
}

TEST(Weld, MatchesBruteForceOnANoisyCloud) {
  // The tolerance is kWeldTolerance of the mesh's diagonal, not an absolute length: in a cloud
  // 200 units across it is 3.5e-4. Each cloud point gets copies 0.4 tolerances from it, which
  // must weld (at most 0.8 apart), and a twin 3 tolerances away, which must not (at least 2.6
  // from every copy). Reference: O(n²) distances against the tolerance computed here, in double.
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-100, 100);
  std::vector<Vec3f> points;
  for (int i = 0; i < 400; ++i)
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
  Eigen::AlignedBox3d box;
  for (const Vec3f& p : points) box.extend(p.cast<double>());
  // The copies move the bounds by under a tolerance: a millionth of the diagonal again.
  const double tolerance = double(kWeldTolerance) * box.diagonal().norm();
  std::normal_distribution<double> gauss;
  const auto offset = [&](double length) {
    const Eigen::Vector3d direction(gauss(random), gauss(random), gauss(random));
    return (length * direction.normalized()).cast<float>().eval();
  };
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
  std::uniform_int_distribution<int> pick(0, 399);
  std::uniform_int_distribution<int> far(0, 9);
  for (int t = 0; t < 1500; ++t) {
    Triangle tri;
    for (int c = 0; c < 3; ++c) {
      tri[c] = Index(positions.size());
      const int k = pick(random);
      positions.push_back(far(random) == 0 ? Vec3f(points[k] + Vec3f(float(3 * tolerance), 0, 0))
                                           : Vec3f(points[k] + offset(0.4 * tolerance)));
    }
    triangles.push_back(tri);
  }
  const WeldedMesh welded = weldByPosition(positions, triangles);
  std::size_t welds = 0, apart = 0;
  for (std::size_t a = 0; a < positions.size(); ++a)
    for (std::size_t b = a + 1; b < positions.size(); ++b) {
      if (welded.renderToParticle[a] == kNoParticle || welded.renderToParticle[b] == kNoParticle)
        continue;
      const double distance = (positions[a] - positions[b]).cast<double>().norm();
      if (distance > 10 * tolerance) continue;  // different cloud points
      const bool close = distance < tolerance;
      (close ? welds : apart) += 1;
      ASSERT_EQ(close, welded.renderToParticle[a] == welded.renderToParticle[b])
          << a << " " << b << ": " << distance / tolerance << " tolerances apart";
    }
  // Both kinds of pair are there to be told apart.
  EXPECT_GT(welds, 1000u);
  EXPECT_GT(apart, 100u);
}

}  // namespace
}  // namespace softbake
