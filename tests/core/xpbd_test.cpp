// The XPBD integrator's own parts (core/dynamics/xpbd): the spring colouring that makes it
// parallel and deterministic, and the meaning of stiffness and damping against the analytic
// damped oscillator. What it shares with backward Euler is in stable_integrators_test.
#include "core/dynamics/xpbd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "test_worlds.hpp"

namespace softbake {
namespace {

TEST(Xpbd, NoTwoSpringsOfOneColourShareAParticle) {
  const SceneTopology topology =
      buildSceneTopology(test::ballScene(*findMaterialPreset("rubber"), 3));
  const Xpbd xpbd(topology);
  const auto colourStart = xpbd.colourStart();
  const auto constraints = xpbd.constraints();
  ASSERT_EQ(colourStart.back(), constraints.size());
  // Every spring is there exactly once (they all have stiffness).
  std::multiset<std::pair<Index, Index>> springs, solved;
  for (const Spring& s : topology.springs) springs.insert({s.a, s.b});
  for (const Xpbd::DistanceConstraint& c : constraints) solved.insert({c.a, c.b});
  EXPECT_EQ(springs, solved);
  // Brute force over each colour.
  for (std::size_t colour = 0; colour + 1 < colourStart.size(); ++colour) {
    std::set<Index> touched;
    for (std::size_t k = colourStart[colour]; k < colourStart[colour + 1]; ++k) {
      EXPECT_TRUE(touched.insert(constraints[k].a).second) << "colour " << colour;
      EXPECT_TRUE(touched.insert(constraints[k].b).second) << "colour " << colour;
    }
  }
  // Greedy colouring needs at most 2·(largest degree) − 1 colours.
  Index largestDegree = 0;
  for (std::size_t i = 0; i < topology.particleCount(); ++i)
    largestDegree =
        std::max(largestDegree, topology.springRowStart[i + 1] - topology.springRowStart[i]);
  EXPECT_LE(colourStart.size() - 1, std::size_t(2 * largestDegree - 1));
}

/// Runs a stretched spring pair for one second of small XPBD steps and compares its extension
/// with the analytic damped oscillator of the same k (N/m), c (N·s/m) and masses: the compliance
/// 1/k and the damping c/k must mean what the forces of the explicit integrator mean.
void expectAnalyticOscillation(double dampingRatio) {
  const double k = 100, m = 1, reduced = m / 2, stretch = 0.1;
  const double c = dampingRatio * 2 * std::sqrt(k * reduced);
  test::StagedScene pair = test::springPair(Scalar(k), Scalar(c), Scalar(m), Scalar(1 + stretch));
  Xpbd xpbd(pair.topology);
  const double h = 1e-4, omega0 = std::sqrt(k / reduced);
  const double omegaD = omega0 * std::sqrt(1 - dampingRatio * dampingRatio);
  double worst = 0;
  for (int n = 1; n <= 10000; ++n) {
    ASSERT_TRUE(xpbd.step(pair.topology, pair.forces, Scalar(h), pair.state, pair.substepStart));
    const double t = n * h;
    const double exact =
        stretch * std::exp(-dampingRatio * omega0 * t) *
        (std::cos(omegaD * t) +
         dampingRatio / std::sqrt(1 - dampingRatio * dampingRatio) * std::sin(omegaD * t));
    const double got = double((pair.state.position[1] - pair.state.position[0]).norm()) - 1;
    worst = std::max(worst, std::abs(got - exact));
  }
  // Over two periods, within 3% of the initial stretch.
  EXPECT_LT(worst, 0.03 * stretch) << "damping ratio " << dampingRatio;
}

TEST(Xpbd, AnUndampedSpringPairOscillatesAtItsNaturalFrequency) {
  expectAnalyticOscillation(0);
}

TEST(Xpbd, DampingIsTheFractionOfCriticalItSays) {
  expectAnalyticOscillation(0.05);
  expectAnalyticOscillation(0.3);
}

TEST(Xpbd, PinnedEndsStayAndTheFreeEndIsPulledBack) {
  test::StagedScene pair = test::springPair(10000, 0, 1, 1.5f);
  pair.topology.inverseMass[0] = 0;
  Xpbd xpbd(pair.topology);
  const Vec3 pinned = pair.state.position[0];
  ASSERT_TRUE(xpbd.step(pair.topology, pair.forces, Scalar(0.01), pair.state, pair.substepStart));
  EXPECT_EQ(pair.state.position[0], pinned);
  EXPECT_EQ(pair.state.velocity[0], Vec3::Zero());
  // By hand: C = 0.5, α̃ = 1/(k·h²) = 1, w = 1, so Δλ = −0.5/2 and x₁ moves back by 0.25.
  EXPECT_NEAR(pair.state.position[1].x(), 1.25, 1e-6);
  EXPECT_NEAR(pair.state.velocity[1].x(), -25, 1e-3);
}

}  // namespace
}  // namespace softbake
