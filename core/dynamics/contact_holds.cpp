#include "core/dynamics/contact_holds.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <functional>

#include "core/dynamics/for_each_particle.hpp"

namespace softbake {

namespace {
/// A particle is held from the start of a step when its expected end is below this fraction of
/// the skin. Under 1, so that a particle let go at the skin, whose expected end is the skin give or
/// take rounding, is not held again at once (its hold pulled it: it is leaving).
constexpr Scalar kExpectedEndInSkins = Scalar(0.98);
/// Expected only over an approach of at most this many skins in the step: a particle creeping onto
/// the plane at the edge of a contact, which the last Δv predicts well. A fast impact changes the
/// body's motion within the step, and holding every particle its last velocity would bring down
/// flattened balls landing at one substep a frame (volume −45%); those are caught after the step.
constexpr Scalar kLongestExpectedApproachInSkins = 2;
}  // namespace

ContactHolds::ContactHolds(const SceneTopology& topology)
    : topology_(topology),
      touchedPlane_(topology.planes.empty() ? 0 : topology.particleCount(), kNoPlane),
      heldPlane_(touchedPlane_),
      expected_(touchedPlane_.size(), 0) {}

std::int32_t ContactHolds::firstTouchedPlane(const Vec3& point) const {
  for (std::size_t p = 0; p < topology_.planes.size(); ++p)
    if (touchesPlane(topology_.planes[p], topology_.settings.skin, point)) return std::int32_t(p);
  return kNoPlane;
}

Scalar ContactHolds::skinSpeed(std::int32_t plane, const Vec3& position, Scalar dt) const {
  return (topology_.settings.skin - heightAbove(topology_.planes[plane], position)) / dt;
}

bool ContactHolds::letGoIfWrong(const ImplicitEuler& solver, Index i) {
  if (!expected_[i] || solver.holdImpulse(i) > 0) return false;
  expected_[i] = 0;
  touchedPlane_[i] = kNoPlane;
  return true;
}

void ContactHolds::holdFor(ImplicitEuler& solver, const SimulationState& state, Scalar dt,
                           bool expect) {
  solver.releaseHolds();
  const Scalar skin = topology_.settings.skin;
  const std::span<const Vec3> lastChange = solver.warmStart();
  const Index n = Index(touchedPlane_.size());
  // Under response "none" bodies pass through planes (the paper's figure 5b): nothing is expected.
  if (expect && topology_.settings.collisions.response != ResponseMode::None)
    forEachParticle(n, [&](Index i) {
      expected_[i] = 0;
      if (touchedPlane_[i] != kNoPlane || topology_.inverseMass[i] == 0) return;
      // Held from the start when its velocity, changed as the last step changed it, takes it
      // into the skin: then the step is not taken again for it (catchImpacts()), which figure 7
      // did in three steps of five, mostly for one or two particles at the edge of a contact.
      const Vec3 expected = state.velocity[i] + lastChange[i];
      for (std::size_t p = 0; p < topology_.planes.size(); ++p) {
        const PlaneCollider& plane = topology_.planes[p];
        const Scalar height = heightAbove(plane, state.position[i]);
        const Scalar approach = -dt * plane.normal.dot(expected);
        if (height - approach < kExpectedEndInSkins * skin &&
            approach <= kLongestExpectedApproachInSkins * skin) {
          touchedPlane_[i] = std::int32_t(p);
          expected_[i] = 1;
          return;
        }
      }
    });
  // In particle order, one thread: the solver's list of holds is in that order on any thread count.
  for (Index i = 0; i < n; ++i) {
    if (touchedPlane_[i] == kNoPlane) continue;
    heldPlane_[i] = touchedPlane_[i];
    const PlaneCollider& plane = topology_.planes[touchedPlane_[i]];
    solver.hold(i, plane.normal, skinSpeed(touchedPlane_[i], state.position[i], dt),
                plane.friction);
  }
}

std::size_t ContactHolds::catchImpacts(const SimulationState& state) {
  return tbb::parallel_reduce(
      tbb::blocked_range<Index>(0, Index(touchedPlane_.size()), kParticleGrain), std::size_t(0),
      [&](const tbb::blocked_range<Index>& range, std::size_t caught) {
        for (Index i = range.begin(); i != range.end(); ++i) {
          if (touchedPlane_[i] != kNoPlane || topology_.inverseMass[i] == 0) continue;
          touchedPlane_[i] = firstTouchedPlane(state.position[i]);
          caught += touchedPlane_[i] != kNoPlane;
        }
        return caught;
      },
      std::plus<>());
}

std::size_t ContactHolds::catchInRound(ImplicitEuler& solver, const SimulationState& state,
                                       Scalar dt) {
  std::size_t changed = 0;
  for (Index i = 0; i < Index(touchedPlane_.size()); ++i) {
    if (topology_.inverseMass[i] == 0) continue;
    if (touchedPlane_[i] != kNoPlane) {
      if (letGoIfWrong(solver, i)) {
        solver.releaseInRound(i);
        ++changed;
      }
      continue;
    }
    const std::int32_t p =
        firstTouchedPlane(state.position[i] + dt * (state.velocity[i] + solver.deltaV(i)));
    if (p == kNoPlane) continue;
    touchedPlane_[i] = heldPlane_[i] = p;
    const PlaneCollider& plane = topology_.planes[p];
    solver.holdInRound(i, plane.normal, skinSpeed(p, state.position[i], dt), plane.friction,
                       state.velocity[i]);
    ++changed;
  }
  return changed;
}

std::size_t ContactHolds::dropWrongExpectations(const ImplicitEuler& solver) {
  std::size_t wrong = 0;
  for (Index i : solver.heldParticles()) wrong += letGoIfWrong(solver, i);
  return wrong;
}

std::size_t ContactHolds::update(const ImplicitEuler& solver) {
  // Every hold is a plane hold. One that pulled its particle towards the plane ends, even where
  // the plane pass caught the particle again (only by rounding).
  std::size_t kept = 0;
  for (Index i : solver.heldParticles()) {
    if (!(solver.holdImpulse(i) > 0)) {
      touchedPlane_[i] = kNoPlane;
    } else if (touchedPlane_[i] == kNoPlane) {
      touchedPlane_[i] = heldPlane_[i];
      ++kept;
    }
  }
  return kept;
}

}  // namespace softbake
