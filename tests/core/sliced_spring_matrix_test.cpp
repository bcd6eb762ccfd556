// The SIMD layout of the implicit step's matrix against the product written out spring by spring
// in double precision: the same matrix, whatever the slices, their padding, the pinned rows and
// columns, and the range of particles asked for.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "core/dynamics/sliced_spring_matrix.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

struct Block {
  Vec3d axis;
  double along, isotropic;
  Vec3d times(const Vec3d& x) const { return along * axis.dot(x) * axis + isotropic * x; }
};

class SlicedSpringMatrixTest : public testing::Test {
 protected:
  void SetUp() override {
    // 162 particles: the last of 21 slices holds two. Icosphere rows are 10 to 12 springs long
    // (edges and bending springs), so slices are padded.
    topology = buildSceneTopology(test::ballScene(*findMaterialPreset("rubber"), 2));
    ASSERT_EQ(topology.particleCount() % SlicedSpringMatrix::kLanes, 2u);
    for (Index pinned : {Index(3), Index(40), Index(161)}) topology.inverseMass[pinned] = 0;
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(-1, 1);
    for (std::size_t s = 0; s < topology.springs.size(); ++s)
      blocks.push_back({Vec3d(uniform(random), uniform(random), uniform(random)).normalized(),
                        2 + uniform(random), 1 + uniform(random)});
    x.assign(topology.particleCount() + SlicedSpringMatrix::kLanes, Vec3::Zero());
    for (Index i = 0; i < topology.particleCount(); ++i)
      x[i] = Vec3(Scalar(uniform(random)), Scalar(uniform(random)), Scalar(uniform(random)));
  }

  SlicedSpringMatrix filled() const {
    SlicedSpringMatrix matrix(topology);
    for (std::size_t s = 0; s < topology.springs.size(); ++s)
      matrix.setSpringBlock(s, blocks[s].axis.cast<Scalar>(), Scalar(blocks[s].along),
                            Scalar(blocks[s].isotropic));
    return matrix;
  }

  /// (M + Σ S)·x spring by spring, pinned rows and columns taken out.
  std::vector<Vec3d> reference() const {
    const std::size_t n = topology.particleCount();
    auto value = [&](Index i) {
      return topology.inverseMass[i] == 0 ? Vec3d::Zero() : Vec3d(x[i].cast<double>());
    };
    std::vector<Vec3d> product(n, Vec3d::Zero());
    for (Index i = 0; i < n; ++i) product[i] = double(topology.mass[i]) * value(i);
    for (std::size_t s = 0; s < topology.springs.size(); ++s) {
      const Spring& spring = topology.springs[s];
      const Vec3d stretch = value(spring.a) - value(spring.b);
      product[spring.a] += blocks[s].times(stretch);
      product[spring.b] -= blocks[s].times(stretch);
    }
    for (Index i = 0; i < n; ++i)
      if (topology.inverseMass[i] == 0) product[i].setZero();
    return product;
  }

  SceneTopology topology;
  std::vector<Block> blocks;
  std::vector<Vec3> x;
};

TEST_F(SlicedSpringMatrixTest, MultipliesAsTheSpringsDo) {
  const SlicedSpringMatrix matrix = filled();
  ASSERT_EQ(matrix.paddedSize(), 21 * SlicedSpringMatrix::kLanes + 1);
  x.resize(matrix.paddedSize(), Vec3::Zero());
  std::vector<Vec3> product(topology.particleCount(), Vec3::Constant(99));
  const double curvature = matrix.multiply(x.data(), product.data(), topology.inverseMass.data(), 0,
                                           topology.particleCount());
  const std::vector<Vec3d> expected = reference();
  double expectedCurvature = 0;
  for (Index i = 0; i < topology.particleCount(); ++i) {
    EXPECT_LT((product[i].cast<double>() - expected[i]).norm(), 1e-5 * (1 + expected[i].norm()))
        << "particle " << i;
    expectedCurvature += x[i].cast<double>().dot(expected[i]);
  }
  EXPECT_EQ(product[3], Vec3::Zero()) << "a pinned row is zero";
  EXPECT_NEAR(curvature, expectedCurvature, 1e-5 * std::abs(expectedCurvature));
}

TEST_F(SlicedSpringMatrixTest, EachSpringHasASlotInTheRowOfEachFreeEnd) {
  const SlicedSpringMatrix matrix(topology);
  std::vector<int> seen(matrix.slotCount(), 0);
  for (Index i = 0; i < topology.particleCount(); ++i)
    for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
      const Index ref = topology.springRefs[r];
      const std::size_t at = (ref & 1) ? matrix.slotAtB(ref >> 1) : matrix.slotAtA(ref >> 1);
      if (topology.inverseMass[i] == 0) {
        EXPECT_EQ(at, SlicedSpringMatrix::kNoSlot) << "a pinned row is empty";
        continue;
      }
      EXPECT_EQ(at, matrix.slot(i, r - topology.springRowStart[i]));
      ++seen.at(at);
    }
  for (std::size_t at = 0; at < seen.size(); ++at) EXPECT_LE(seen[at], 1) << "slot " << at;
}

TEST_F(SlicedSpringMatrixTest, AnyRangeOfWholeSlicesGivesTheSameBytes) {
  const SlicedSpringMatrix matrix = filled();
  x.resize(matrix.paddedSize(), Vec3::Zero());
  const std::size_t n = topology.particleCount();
  std::vector<Vec3> whole(n), pieces(n);
  const double total = matrix.multiply(x.data(), whole.data(), topology.inverseMass.data(), 0, n);
  double sum = 0;
  for (std::size_t begin = 0; begin < n; begin += 3 * SlicedSpringMatrix::kLanes)
    sum += matrix.multiply(x.data(), pieces.data(), topology.inverseMass.data(), begin,
                           std::min(n, begin + 3 * SlicedSpringMatrix::kLanes));
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(whole[i], pieces[i]) << "particle " << i;
  EXPECT_NEAR(sum, total, 1e-12 * std::abs(total));
}

TEST_F(SlicedSpringMatrixTest, AvxAndSseRegistersGiveTheSameBytes) {
  // Lane by lane the same operations, without fused multiply-adds: a bake is the same on a
  // processor with AVX2 as on one without.
  SlicedSpringMatrix matrix = filled();
  x.resize(matrix.paddedSize(), Vec3::Zero());
  const std::size_t n = topology.particleCount();
  std::vector<Vec3> wide(n), narrow(n);
  const double wideSum = matrix.multiply(x.data(), wide.data(), topology.inverseMass.data(), 0, n);
  const bool hadAvx2 = matrix.usesAvx2();
  matrix.useAvx2(false);
  ASSERT_FALSE(matrix.usesAvx2());
  const double narrowSum =
      matrix.multiply(x.data(), narrow.data(), topology.inverseMass.data(), 0, n);
  EXPECT_EQ(wideSum, narrowSum);
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(wide[i], narrow[i]) << "particle " << i;
  if (!hadAvx2) std::puts("note: this processor has no AVX2; both runs used SSE2");
}

}  // namespace
}  // namespace softbake
