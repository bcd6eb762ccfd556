// The contact springs' share of the implicit system (core/dynamics/contact_springs.hpp) against a
// dense matrix built in double from the stencils' definition: the product, the diagonal blocks and
// the right-hand side.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <Eigen/Dense>

#include "core/dynamics/contact_springs.hpp"

namespace softbake {
namespace {

struct Springs {
  std::vector<ContactStencil> stencils;
  std::vector<Scalar> inverseMass;
};

/// `count` stencils over `particles` particles, some corners fixed, one particle pinned.
Springs randomSprings(std::size_t particles, std::size_t count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> unit(0, 1);
  Springs springs;
  springs.inverseMass.resize(particles);
  for (Scalar& w : springs.inverseMass) w = Scalar(1) / (Scalar(0.5) + unit(random));
  springs.inverseMass[3] = 0;  // pinned: named by stencils, never moved
  for (std::size_t s = 0; s < count; ++s) {
    ContactStencil stencil;
    std::vector<Index> picked;
    while (picked.size() < 4) {
      const Index p = Index(random() % particles);
      if (std::find(picked.begin(), picked.end(), p) == picked.end()) picked.push_back(p);
    }
    float b0 = unit(random), b1 = unit(random) * (1 - b0);
    const std::array<Scalar, 4> weights{1, -(1 - b0 - b1), -b0, -b1};
    for (int k = 0; k < 4; ++k) {
      stencil.particle[k] = (s % 3 == 0 && k == 2) ? ContactStencil::kFixed : picked[k];
      stencil.weight[k] = stencil.particle[k] == ContactStencil::kFixed ? 0 : weights[k];
    }
    stencil.normal =
        Vec3(unit(random) - 0.5f, unit(random) - 0.5f, unit(random) - 0.5f).normalized();
    stencil.offset = -Scalar(0.001);
    springs.stencils.push_back(stencil);
  }
  return springs;
}

/// Σ c·g·gᵀ over the active stencils, with c = kStiffness / Σ w²/m, in double.
Eigen::MatrixXd denseContactMatrix(const Springs& springs, const std::vector<bool>& active,
                                   std::size_t particles) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * particles, 3 * particles);
  for (std::size_t s = 0; s < springs.stencils.size(); ++s) {
    if (!active[s]) continue;
    const ContactStencil& stencil = springs.stencils[s];
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * particles);
    double resistance = 0;
    for (int k = 0; k < 4; ++k) {
      const Index p = stencil.particle[k];
      if (p == ContactStencil::kFixed || springs.inverseMass[p] == 0) continue;
      g.segment<3>(3 * p) = double(stencil.weight[k]) * stencil.normal.cast<double>();
      resistance += double(stencil.weight[k]) * stencil.weight[k] * springs.inverseMass[p];
    }
    a += (double(ContactSprings::kStiffness) / resistance) * g * g.transpose();
  }
  return a;
}

TEST(ContactSprings, ProductDiagonalAndRightHandSideMatchADenseReference) {
  constexpr std::size_t kParticles = 40;
  const Springs springs = randomSprings(kParticles, 60, 7);
  ContactSprings contacts(kParticles);
  contacts.set(springs.stencils, springs.inverseMass.data());
  std::mt19937 random(11);
  std::uniform_real_distribution<float> unit(-1, 1);
  std::vector<Vec3> x0(kParticles), v0(kParticles), x(kParticles + 1, Vec3::Zero());
  for (std::size_t i = 0; i < kParticles; ++i) {
    x0[i] = Vec3(unit(random), unit(random), unit(random)) * Scalar(0.01);
    v0[i] = Vec3(unit(random), unit(random), unit(random));
    x[i] = Vec3(unit(random), unit(random), unit(random));
  }
  for (Index p = 0; p < kParticles; ++p)
    if (springs.inverseMass[p] == 0) {
      x[p].setZero();   // pinned entries of a CG vector are 0
      v0[p].setZero();  // and a pinned particle stands still
    }
  const Scalar h = Scalar(1.0 / 48);
  const Vec3 gravity(0, Scalar(-9.81), 0);
  contacts.begin(x0.data(), v0.data(), gravity, h);
  // The active set begin() chose, recomputed from its definition: the particle would end within
  // the gap under its own velocity and gravity.
  std::vector<bool> active(springs.stencils.size());
  std::size_t activeCount = 0;
  for (std::size_t s = 0; s < springs.stencils.size(); ++s) {
    const ContactStencil& stencil = springs.stencils[s];
    double c = stencil.offset, approach = 0, fall = 0;
    for (int k = 0; k < 4; ++k) {
      const Index p = stencil.particle[k];
      if (p == ContactStencil::kFixed) continue;
      c += double(stencil.weight[k]) * stencil.normal.cast<double>().dot(x0[p].cast<double>());
      approach +=
          double(stencil.weight[k]) * stencil.normal.cast<double>().dot(v0[p].cast<double>());
      if (springs.inverseMass[p] != 0)
        fall +=
            double(stencil.weight[k]) * stencil.normal.cast<double>().dot(gravity.cast<double>());
    }
    active[s] = c + h * (approach + h * fall) < 0;
    activeCount += active[s];
  }
  ASSERT_EQ(contacts.activeCount(), activeCount);
  ASSERT_GT(activeCount, 10u);
  ASSERT_LT(activeCount, springs.stencils.size());

  const Eigen::MatrixXd a = denseContactMatrix(springs, active, kParticles);
  Eigen::VectorXd xd(3 * kParticles);
  for (std::size_t i = 0; i < kParticles; ++i) xd.segment<3>(3 * i) = x[i].cast<double>();
  const Eigen::VectorXd expected = a * xd;

  // The product as the solver runs it: over chunks of particles, here two, which split stencils.
  std::vector<Vec3> out(kParticles, Vec3::Zero());
  const double curvature = contacts.multiply(x.data(), out.data(), 0, 17) +
                           contacts.multiply(x.data(), out.data(), 17, kParticles);
  for (std::size_t i = 0; i < kParticles; ++i)
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(out[i][d], expected[3 * i + d], 1e-3 * (1 + std::abs(expected[3 * i + d])))
          << "particle " << i;
  EXPECT_NEAR(curvature, xd.dot(expected), 1e-4 * xd.dot(expected));

  // Diagonal blocks and right-hand side: base + Σ c·w²·n·nᵀ and base − c·w·n·(C₀/h + g·v₀).
  using Mat3 = ContactSprings::Mat3;
  std::vector<Vec3> rhs(kParticles, Vec3(1, 2, 3));
  std::vector<Mat3> inverseDiagonal(kParticles, Mat3::Identity());
  const std::span<const Index> touched = contacts.touched();
  for (std::size_t row = 0; row < touched.size(); ++row) {
    contacts.keepBaseDiagonal(row, Mat3::Identity() * Scalar(2));
    contacts.keepBaseRhs(row, Vec3(1, 2, 3));
  }
  contacts.applyRows(rhs.data(), inverseDiagonal.data(), 0, 17);
  contacts.applyRows(rhs.data(), inverseDiagonal.data(), 17, kParticles);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(3 * kParticles);
  for (std::size_t s = 0; s < springs.stencils.size(); ++s) {
    if (!active[s]) continue;
    const ContactStencil& stencil = springs.stencils[s];
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * kParticles);
    double c0 = stencil.offset, resistance = 0;
    for (int k = 0; k < 4; ++k) {
      const Index p = stencil.particle[k];
      if (p == ContactStencil::kFixed) continue;
      c0 += double(stencil.weight[k]) * stencil.normal.cast<double>().dot(x0[p].cast<double>());
      if (springs.inverseMass[p] == 0) continue;
      g.segment<3>(3 * p) = double(stencil.weight[k]) * stencil.normal.cast<double>();
      resistance += double(stencil.weight[k]) * stencil.weight[k] * springs.inverseMass[p];
    }
    Eigen::VectorXd v(3 * kParticles);
    for (std::size_t i = 0; i < kParticles; ++i) v.segment<3>(3 * i) = v0[i].cast<double>();
    b -= (double(ContactSprings::kStiffness) / resistance) * (c0 / h + g.dot(v)) * g;
  }
  for (std::size_t row = 0; row < touched.size(); ++row) {
    const Index i = touched[row];
    const Eigen::Matrix3d block = 2 * Eigen::Matrix3d::Identity() + a.block<3, 3>(3 * i, 3 * i);
    const Eigen::Matrix3d inverse = inverseDiagonal[i].cast<double>();
    EXPECT_LT((inverse * block - Eigen::Matrix3d::Identity()).norm(), 1e-3) << "particle " << i;
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(rhs[i][d], 1 + d + b[3 * i + d], 1e-3 * (1 + std::abs(b[3 * i + d])))
          << "particle " << i;
  }
  // Particles no stencil moves keep their rows; the pinned one is never touched.
  EXPECT_EQ(contacts.row(3), ContactSprings::kNoRow);
}

/// One particle against a fixed point below it along +y, with a 1 mm gap: C = y − y_fixed − gap.
ContactStencil particleOverFixedPoint() {
  ContactStencil stencil;
  stencil.particle = {0, ContactStencil::kFixed, ContactStencil::kFixed, ContactStencil::kFixed};
  stencil.weight = {1, 0, 0, 0};
  stencil.normal = Vec3::UnitY();
  stencil.offset = -Scalar(0.001);
  return stencil;
}

TEST(ContactSprings, AnActiveSpringThatPullsIsLetGoAndOneThatEndsInsideIsTakenIn) {
  const ContactStencil stencil = particleOverFixedPoint();
  const std::vector<Scalar> inverseMass{1};
  ContactSprings contacts(1);
  contacts.set(std::span<const ContactStencil>(&stencil, 1), inverseMass.data());
  const Scalar h = Scalar(0.01);
  const std::vector<Vec3> x0{Vec3(0, Scalar(0.0015), 0)};
  // Falling at 1 m/s: it would end 1 cm down, inside the gap: active.
  std::vector<Vec3> v0{Vec3(0, -1, 0)};
  contacts.begin(x0.data(), v0.data(), Vec3::Zero(), h);
  EXPECT_EQ(contacts.activeCount(), 1u);
  // A solve that sent it up instead: the spring pulled, so it lets go.
  std::vector<Vec3> deltaV{Vec3(0, 2, 0)};
  EXPECT_EQ(contacts.update(v0.data(), deltaV.data(), h, Scalar(1e-4)), 1u);
  EXPECT_EQ(contacts.activeCount(), 0u);
  // Rising, it is inactive; a solve that ends it inside takes it in.
  v0[0] = Vec3(0, 1, 0);
  contacts.begin(x0.data(), v0.data(), Vec3::Zero(), h);
  EXPECT_EQ(contacts.activeCount(), 0u);
  deltaV[0] = Vec3(0, -2, 0);
  EXPECT_EQ(contacts.update(v0.data(), deltaV.data(), h, Scalar(1e-4)), 1u);
  EXPECT_EQ(contacts.activeCount(), 1u);
}

/// The augmented-Lagrangian step raises an ordinary spring that a solve left inside by what it is
/// short of, and never a fitted one: a fit's hold stops its vertex but never pushes it, and springs
/// raised beside such holds pushed an assembly's fitted parts out of their fits (64 MJ in 2 s).
TEST(ContactSprings, AFittedSpringKeepsItsOwnForceWhereAnOrdinaryOneIsRaised) {
  for (bool fitted : {false, true}) {
    ContactStencil stencil = particleOverFixedPoint();
    stencil.fitted = fitted;
    const std::vector<Scalar> inverseMass{1};
    ContactSprings contacts(1);
    contacts.set(std::span<const ContactStencil>(&stencil, 1), inverseMass.data());
    contacts.keepBaseDiagonal(0, ContactSprings::Mat3::Identity());
    contacts.keepBaseRhs(0, Vec3::Zero());
    const Scalar h = Scalar(0.01);
    const std::vector<Vec3> x0{Vec3(0, Scalar(0.0015), 0)}, v0{Vec3(0, -1, 0)};
    contacts.begin(x0.data(), v0.data(), Vec3::Zero(), h);
    ASSERT_EQ(contacts.activeCount(), 1u);
    std::vector<Vec3> rhs(1), after(1);
    std::vector<ContactSprings::Mat3> inverseDiagonal(1);
    contacts.applyRows(rhs.data(), inverseDiagonal.data(), 0, 1);
    // The solve left it 1.5 mm short of its gap: 0.5 mm beyond the plane.
    const std::vector<Vec3> deltaV{Vec3(0, Scalar(0.8), 0)};
    EXPECT_EQ(contacts.update(v0.data(), deltaV.data(), h, Scalar(1e-4)), fitted ? 0u : 1u);
    EXPECT_EQ(contacts.activeCount(), 1u) << "it still pushes";
    contacts.applyRows(after.data(), inverseDiagonal.data(), 0, 1);
    if (fitted)
      EXPECT_EQ(after[0], rhs[0]) << "a fit's spring asks no more than its own force";
    else
      EXPECT_GT(after[0].y(), rhs[0].y()) << "raised by what it was short of";
  }
}

}  // namespace
}  // namespace softbake
