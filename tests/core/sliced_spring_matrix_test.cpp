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

/// What SlicedSpringMatrix::assemble() writes, kept per particle and per slot.
struct Assembled {
  explicit Assembled(const SlicedSpringMatrix& matrix, std::size_t n)
      : force(n, Vec3::Constant(7)),
        diagonal(9 * n, 7),
        termX(matrix.slotCount(), 7),
        termY(matrix.slotCount(), 7),
        termZ(matrix.slotCount(), 7) {}
  SlicedSpringMatrix::AssemblyOutput output() {
    return {force.data(), diagonal.data(), termX.data(), termY.data(), termZ.data()};
  }
  std::vector<Vec3> force;
  std::vector<Scalar> diagonal, termX, termY, termZ;
};

class SpringAssemblyTest : public SlicedSpringMatrixTest {
 protected:
  void SetUp() override {
    SlicedSpringMatrixTest::SetUp();
    std::mt19937 random(11);
    std::uniform_real_distribution<double> uniform(-1, 1);
    velocity.resize(topology.particleCount());
    for (Vec3& v : velocity)
      v = Vec3(Scalar(uniform(random)), Scalar(uniform(random)), Scalar(uniform(random)));
    // Spring 5 of zero length: no force and a zero block, as computeSpringForces() has it.
    x[topology.springs[5].b] = x[topology.springs[5].a];
    x.resize(topology.particleCount());
  }
  SlicedSpringMatrix::AssemblyInput input() const {
    return {x.data(), velocity.data(), Vec3(0, Scalar(-9.81), 0), kTimeStep};
  }
  static constexpr Scalar kTimeStep = Scalar(1.0 / 96);
  std::vector<Vec3> velocity;
};

TEST_F(SpringAssemblyTest, EachRowHoldsItsSpringsAsTheirOwnFormulasGiveThem) {
  // The reference walks the springs once each, in double, and adds each one's share to both ends.
  const std::size_t n = topology.particleCount();
  SlicedSpringMatrix matrix(topology);
  Assembled out(matrix, n);
  matrix.assemble(input(), out.output(), 0, n);

  const double h = kTimeStep, h2 = h * h;
  std::vector<Vec3d> force(n), term(matrix.slotCount(), Vec3d::Zero());
  std::vector<Eigen::Matrix3d> diagonal(n);
  for (std::size_t i = 0; i < n; ++i) {
    force[i] = double(topology.mass[i]) * Vec3d(0, -9.81, 0);
    diagonal[i] = double(topology.mass[i]) * Eigen::Matrix3d::Identity();
  }
  for (std::size_t s = 0; s < topology.springs.size(); ++s) {
    const Spring& spring = topology.springs[s];
    const Vec3d d = (x[spring.b] - x[spring.a]).cast<double>();
    const Vec3d dv = (velocity[spring.b] - velocity[spring.a]).cast<double>();
    const double length = d.norm();
    if (length == 0) continue;
    const Vec3d axis = d / length;
    const Vec3d f =
        (spring.stiffness * (length - spring.restLength) + spring.damping * dv.dot(axis)) * axis;
    const double transverse = std::max(0.0, 1 - spring.restLength / length);
    const Eigen::Matrix3d stiffness =
        spring.stiffness *
        ((1 - transverse) * axis * axis.transpose() + transverse * Eigen::Matrix3d::Identity());
    const Eigen::Matrix3d block = h * spring.damping * axis * axis.transpose() + h2 * stiffness;
    force[spring.a] += f, force[spring.b] -= f;
    diagonal[spring.a] += block, diagonal[spring.b] += block;
    if (matrix.slotAtA(s) != SlicedSpringMatrix::kNoSlot)
      term[matrix.slotAtA(s)] = h2 * stiffness * dv;
    if (matrix.slotAtB(s) != SlicedSpringMatrix::kNoSlot)
      term[matrix.slotAtB(s)] = -h2 * stiffness * dv;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (topology.inverseMass[i] == 0) continue;  // an empty row: its outputs mean nothing
    EXPECT_LT((out.force[i].cast<double>() - force[i]).norm(), 1e-4 * (1 + force[i].norm()))
        << "particle " << i;
    const Eigen::Map<const Eigen::Matrix<Scalar, 3, 3>> got(&out.diagonal[9 * i]);
    EXPECT_LT((got.cast<double>() - diagonal[i]).norm(), 1e-5 * diagonal[i].norm())
        << "particle " << i;
    for (Index r = topology.springRowStart[i]; r < topology.springRowStart[i + 1]; ++r) {
      const std::size_t at = matrix.slot(Index(i), r - topology.springRowStart[i]);
      const Vec3d gotTerm(out.termX[at], out.termY[at], out.termZ[at]);
      EXPECT_LT((gotTerm - term[at]).norm(), 1e-5 * (1e-3 + term[at].norm())) << "slot " << at;
    }
  }
  const Spring& collapsed = topology.springs[5];
  for (const std::size_t at : {matrix.slotAtA(5), matrix.slotAtB(5)})
    if (at != SlicedSpringMatrix::kNoSlot) {
      EXPECT_EQ(matrix.along(at), 0) << "spring " << collapsed.a << "-" << collapsed.b;
      EXPECT_EQ(matrix.isotropic(at), 0);
    }

  // The blocks it set are the product's: A·x against the reference's blocks, spring by spring.
  std::vector<Vec3> probe(matrix.paddedSize(), Vec3::Zero()), product(n);
  for (std::size_t i = 0; i < n; ++i)
    if (topology.inverseMass[i] != 0) probe[i] = Vec3(Scalar(i % 3), 1, Scalar(i % 5) - 2);
  matrix.multiply(probe.data(), product.data(), topology.inverseMass.data(), 0, n);
  std::vector<Vec3d> expected(n);
  for (std::size_t i = 0; i < n; ++i)
    expected[i] = double(topology.mass[i]) * probe[i].cast<double>();
  for (std::size_t s = 0; s < topology.springs.size(); ++s) {
    const Spring& spring = topology.springs[s];
    const Vec3d d = (x[spring.b] - x[spring.a]).cast<double>();
    const double length = d.norm();
    if (length == 0) continue;
    const Vec3d axis = d / length;
    const double transverse = std::max(0.0, 1 - spring.restLength / length);
    const Eigen::Matrix3d block =
        (h * spring.damping + h2 * spring.stiffness * (1 - transverse)) * axis * axis.transpose() +
        h2 * spring.stiffness * transverse * Eigen::Matrix3d::Identity();
    const Vec3d stretch = (probe[spring.a] - probe[spring.b]).cast<double>();
    expected[spring.a] += block * stretch, expected[spring.b] -= block * stretch;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (topology.inverseMass[i] == 0) continue;
    EXPECT_LT((product[i].cast<double>() - expected[i]).norm(), 1e-5 * (1 + expected[i].norm()))
        << "particle " << i;
  }
}

TEST_F(SpringAssemblyTest, IsTheSameBytesInAvxAndSseRegistersAndForAnyRangeOfWholeSlices) {
  const std::size_t n = topology.particleCount();
  SlicedSpringMatrix whole(topology), pieces(topology), narrow(topology);
  Assembled a(whole, n), b(pieces, n), c(narrow, n);
  whole.assemble(input(), a.output(), 0, n);
  for (std::size_t begin = 0; begin < n; begin += 2 * SlicedSpringMatrix::kLanes)
    pieces.assemble(input(), b.output(), begin,
                    std::min(n, begin + 2 * SlicedSpringMatrix::kLanes));
  narrow.useAvx2(false);
  narrow.assemble(input(), c.output(), 0, n);
  for (const Assembled* other : {&b, &c}) {
    EXPECT_EQ(a.force, other->force);
    EXPECT_EQ(a.diagonal, other->diagonal);
    EXPECT_EQ(a.termX, other->termX);
    EXPECT_EQ(a.termY, other->termY);
    EXPECT_EQ(a.termZ, other->termZ);
  }
  for (std::size_t at = 0; at < whole.slotCount(); ++at) {
    for (const SlicedSpringMatrix* other : {&pieces, &narrow}) {
      EXPECT_EQ(whole.axis(at), other->axis(at)) << "slot " << at;
      EXPECT_EQ(whole.along(at), other->along(at)) << "slot " << at;
      EXPECT_EQ(whole.isotropic(at), other->isotropic(at)) << "slot " << at;
    }
  }
}

}  // namespace
}  // namespace softbake
