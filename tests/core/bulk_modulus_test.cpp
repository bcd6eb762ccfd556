// The bulk term of closed bodies (Material::bulkModulus): P = nRT/V + K·(1 − V/V_rest). Checked
// against independent references: the implicit step's system rebuilt densely in double precision,
// the energy's closed form, the explicit bound's mode from the eigenvalue it bounds; and by what
// it is for, a ball keeping its volume under a ten times heavier one.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "core/dynamics/energy.hpp"
#include "core/dynamics/implicit_euler.hpp"
#include "core/dynamics/stability.hpp"
#include "core/simulator.hpp"
#include "test_worlds.hpp"

namespace softbake {
namespace {

/// ∂V/∂x of every particle of `body`, in double, from the positions.
Eigen::VectorXd volumeGradient(const SceneTopology& topology, const std::vector<Vec3>& x) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * Eigen::Index(topology.particleCount()));
  for (const Triangle& t : topology.triangles) {
    const Vec3d a = x[t[0]].cast<double>(), b = x[t[1]].cast<double>(), c = x[t[2]].cast<double>();
    const Vec3d third = (b - a).cross(c - a) / 6;
    for (Index corner : t) g.segment<3>(3 * corner) += third;
  }
  return g;
}

/// The implicit step's system for one closed body, assembled densely in double from the formulas
/// alone (implicit_euler.hpp, sliced_spring_matrix.hpp): A = M + Σ S_s (+ c·g·gᵀ with c = h²·K/V₀
/// when `withBulk`), b = h·f₀ + h²·K·v₀.
struct DenseSystem {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
};

DenseSystem denseSystem(const SceneTopology& topology, const SimulationState& state,
                        const ForceBuffers& forces, double h, bool withBulk) {
  const Eigen::Index n = Eigen::Index(topology.particleCount());
  DenseSystem system{Eigen::MatrixXd::Zero(3 * n, 3 * n), Eigen::VectorXd::Zero(3 * n)};
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  for (Eigen::Index i = 0; i < n; ++i) {
    system.A.block<3, 3>(3 * i, 3 * i) += double(topology.mass[i]) * I;
    system.b.segment<3>(3 * i) +=
        h * double(topology.mass[i]) * topology.settings.gravity.cast<double>();
  }
  for (const Spring& s : topology.springs) {
    const Vec3d d = (state.position[s.b] - state.position[s.a]).cast<double>();
    const double l = d.norm();
    const Vec3d axis = d / l;
    const Vec3d dv = (state.velocity[s.b] - state.velocity[s.a]).cast<double>();
    const double k = s.stiffness, c = s.damping, L = s.restLength;
    const Vec3d f = (k * (l - L) + c * dv.dot(axis)) * axis;  // on a
    const double t = std::max(0.0, 1 - L / l);
    const Eigen::Matrix3d stiffness = k * ((1 - t) * axis * axis.transpose() + t * I);
    const Eigen::Matrix3d block = h * c * axis * axis.transpose() + h * h * stiffness;
    const Eigen::Index a = s.a, b = s.b;
    system.A.block<3, 3>(3 * a, 3 * a) += block;
    system.A.block<3, 3>(3 * b, 3 * b) += block;
    system.A.block<3, 3>(3 * a, 3 * b) -= block;
    system.A.block<3, 3>(3 * b, 3 * a) -= block;
    system.b.segment<3>(3 * a) += h * f + h * h * stiffness * dv;
    system.b.segment<3>(3 * b) += -h * f - h * h * stiffness * dv;
  }
  const Eigen::VectorXd g = volumeGradient(topology, state.position);
  const double pressure = forces.bodyPressure[0];
  system.b += h * pressure * g;
  if (withBulk) {
    const Body& body = topology.bodies[0];
    const double coefficient = h * h * double(body.material.bulkModulus) / body.restVolume;
    system.A += coefficient * g * g.transpose();
    Eigen::VectorXd v(3 * n);
    for (Eigen::Index i = 0; i < n; ++i) v.segment<3>(3 * i) = state.velocity[i].cast<double>();
    system.b -= coefficient * g * g.dot(v);
  }
  return system;
}

/// A small ball squeezed: every particle moving inwards, so its volume shrinks fast and the bulk
/// term's share of the system is large.
test::StagedScene squeezedBall(Scalar bulkModulus) {
  Material material = *findMaterialPreset("rubber");
  material.bulkModulus = bulkModulus;
  SceneSetup scene = test::ballScene(material, 1, 0.5f, Vec3f(0, 1, 0), false, false);
  test::StagedScene staged(buildSceneTopology(scene));
  for (std::size_t i = 0; i < staged.state.particleCount(); ++i)
    staged.state.velocity[i] = -2 * (staged.state.position[i] - Vec3(0, 1, 0));
  computeVolumes(staged.topology, staged.state, staged.forces);
  computePressureForces(staged.topology, staged.state, staged.forces);
  return staged;
}

TEST(BulkModulus, TheImplicitStepSolvesTheDenseSystemWithItsRankOneBlock) {
  test::StagedScene ball = squeezedBall(1e6f);
  const SimulationState start = ball.state;
  const double h = 1.0 / 24;
  ImplicitEuler solver(ball.topology);
  ASSERT_TRUE(solver.step(ball.topology, ball.forces, Scalar(h), ball.state, ball.substepStart));
  Eigen::VectorXd dv(3 * Eigen::Index(start.particleCount()));
  for (std::size_t i = 0; i < start.particleCount(); ++i)
    dv.segment<3>(3 * Eigen::Index(i)) = solver.warmStart()[i].cast<double>();

  // The residual recomputed here, not taken from the solver: within its tolerance (and float's
  // rounding) of the dense system with the bulk block.
  const DenseSystem withBulk = denseSystem(ball.topology, start, ball.forces, h, true);
  const double residual = (withBulk.b - withBulk.A * dv).norm() / withBulk.b.norm();
  EXPECT_LT(residual, 1.2 * ImplicitEuler::kTolerance);
  // Without the block the same Δv is far from solving the system: the block is what the step
  // solved (a solver that left it out would pass the check below instead).
  const DenseSystem without = denseSystem(ball.topology, start, ball.forces, h, false);
  EXPECT_GT((without.b - without.A * dv).norm() / without.b.norm(), 5 * ImplicitEuler::kTolerance);
  // And the exact solution's volume rate is what the step's is, to CG's accuracy.
  const Eigen::VectorXd exact = withBulk.A.ldlt().solve(withBulk.b);
  const Eigen::VectorXd g = volumeGradient(ball.topology, start.position);
  Eigen::VectorXd v0(dv.size());
  for (std::size_t i = 0; i < start.particleCount(); ++i)
    v0.segment<3>(3 * Eigen::Index(i)) = start.velocity[i].cast<double>();
  const double rate = g.dot(v0 + dv), exactRate = g.dot(v0 + exact);
  EXPECT_NEAR(rate, exactRate, 0.05 * std::abs(g.dot(v0)));
  EXPECT_LT(std::abs(exactRate), 0.2 * std::abs(g.dot(v0))) << "the bulk term stops the squeeze";
}

TEST(BulkModulus, ItsEnergyIsTheClosedForm) {
  Material material = *findMaterialPreset("jelly");
  material.pressure = 0;  // the bulk term alone
  const SceneTopology topology =
      buildSceneTopology(test::ballScene(material, 3, 0.5f, Vec3f(0, 0, 0), false, false));
  const Body& body = topology.bodies[0];
  for (double scale : {0.8, 0.95, 1.0, 1.1}) {
    SimulationState state = initialState(topology);
    for (Vec3& x : state.position) x *= Scalar(scale);
    const double volume = body.restVolume * scale * scale * scale;
    const double expected = 0.5 * double(material.bulkModulus) / body.restVolume *
                            (volume - body.restVolume) * (volume - body.restVolume);
    const Energy energy = computeEnergy(topology, state);
    EXPECT_NEAR(energy.bulk, expected, 1e-4 * expected + 1e-12) << "scale " << scale;
    EXPECT_EQ(energy.gas, 0);
  }
}

TEST(BulkModulus, PressureIsTheGasLawPlusTheBulkTerm) {
  const Material rubber = *findMaterialPreset("rubber");
  ASSERT_GT(rubber.bulkModulus, 0);
  const SceneTopology topology =
      buildSceneTopology(test::ballScene(rubber, 3, 0.5f, Vec3f(0, 0, 0), false, false));
  const Body& body = topology.bodies[0];
  const double v0 = body.restVolume;
  EXPECT_DOUBLE_EQ(bodyPressure(body, v0), body.gasAmount / v0);
  EXPECT_DOUBLE_EQ(bodyPressure(body, 0.9 * v0),
                   body.gasAmount / (0.9 * v0) + double(rubber.bulkModulus) * 0.1);
  Material balloon = *findMaterialPreset("balloon");
  EXPECT_EQ(balloon.bulkModulus, 0) << "a balloon keeps its gas alone";
  const SceneTopology gas =
      buildSceneTopology(test::ballScene(balloon, 3, 0.5f, Vec3f(0, 0, 0), false, false));
  EXPECT_DOUBLE_EQ(bodyPressure(gas.bodies[0], 0.9 * v0), gas.bodies[0].gasAmount / (0.9 * v0));
}

/// The explicit bound counts the bulk term's mode: its ω² is the largest eigenvalue of
/// M⁻¹·(K/V₀)·g·gᵀ, computed here by power iteration on the dense matrix.
TEST(BulkModulus, TheExplicitBoundCountsItsMode) {
  Material material = *findMaterialPreset("rubber");
  material.bulkModulus = 0;
  const SceneSetup gasOnly = test::ballScene(material, 2, 0.5f, Vec3f(0, 1, 0), false, false);
  material.bulkModulus = 5e7f;
  const SceneSetup stiff = test::ballScene(material, 2, 0.5f, Vec3f(0, 1, 0), false, false);
  const SceneTopology topology = buildSceneTopology(stiff);
  const double without = computeStabilityBound(buildSceneTopology(gasOnly)).maxTimeStep;
  const double with = computeStabilityBound(topology).maxTimeStep;
  EXPECT_LT(with, 0.5 * without) << "a stiff bulk term lowers the bound";

  const Eigen::VectorXd g = volumeGradient(topology, topology.restPosition);
  double mode = 0;
  for (Eigen::Index k = 0; k < g.size(); ++k)
    mode += g[k] * g[k] * double(topology.inverseMass[std::size_t(k / 3)]);
  mode *= double(material.bulkModulus) / topology.bodies[0].restVolume;
  // The bound is at most the time step of the bulk mode alone (γ = 0: h < 2/ω).
  EXPECT_LE(with, 2 / std::sqrt(mode) * (1 + 1e-6));

  // And explicit Euler at "auto" substeps under it stays bounded.
  SceneSetup scene = stiff;
  scene.settings.integrator = IntegratorKind::Explicit;
  scene.settings.gravity = Vec3(0, -9.81f, 0);
  scene.planes.push_back(PlaneCollider{});
  Simulator simulator(buildSceneTopology(scene));
  for (int frame = 2; frame <= 12; ++frame) ASSERT_NO_THROW(simulator.advanceToFrame(frame));
}

/// What the term is for: a rubber ball under a ball ten times heavier keeps its volume within 5%
/// on every frame, landing included, under both stable integrators; under the gas law alone it
/// does not.
class BulkModulusUnderLoad : public testing::TestWithParam<IntegratorKind> {};

double worstVolumeChange(IntegratorKind integrator, Scalar bulkModulus) {
  SceneSetup scene;
  scene.settings.integrator = integrator;
  scene.planes.push_back(PlaneCollider{});
  Material rubber = *findMaterialPreset("rubber");
  rubber.bulkModulus = bulkModulus;
  BodySetup below;
  below.name = "below";
  below.mesh = makeIcosphere(3, 0.4f, Vec3f(0, 0.45f, 0));
  below.material = rubber;
  below.mass = 1;
  BodySetup heavy = below;
  heavy.name = "heavy";
  heavy.mesh = makeIcosphere(3, 0.3f, Vec3f(0.02f, 1.25f, 0.01f));
  heavy.material = *findMaterialPreset("stiff");
  heavy.mass = 10;
  scene.bodies = {below, heavy};
  Simulator simulator(buildSceneTopology(scene));
  const double rest = simulator.topology().bodies[0].restVolume;
  double worst = 0;
  for (int frame = 2; frame <= 36; ++frame) {
    simulator.advanceToFrame(frame);
    worst = std::max(worst, std::abs(simulator.forces().bodyVolume[0] / rest - 1));
  }
  return worst;
}

TEST_P(BulkModulusUnderLoad, ARubberBallUnderATenTimesHeavierOneKeepsItsVolume) {
  const Scalar preset = findMaterialPreset("rubber")->bulkModulus;
  EXPECT_LT(worstVolumeChange(GetParam(), preset), 0.05);
  EXPECT_GT(worstVolumeChange(GetParam(), 0), 0.05) << "the load is heavy enough to tell";
}

INSTANTIATE_TEST_SUITE_P(Integrators, BulkModulusUnderLoad,
                         testing::Values(IntegratorKind::Implicit, IntegratorKind::Xpbd),
                         [](const testing::TestParamInfo<IntegratorKind>& kind) {
                           return std::string(integratorName(kind.param));
                         });

}  // namespace
}  // namespace softbake
