#pragma once
/// The plane contacts the implicit integrator carries from one substep into the next (Baraff &
/// Witkin, "Large Steps in Cloth Simulation", §5.3 and §6).
///
/// The plane pass moves a particle that crossed a plane back onto it. After a step larger than the
/// springs' own time scale (k·h²/m > 1) that move, made while the particle's neighbours stay where
/// the step left them, stores more energy in the springs than the particle's kinetic energy, which
/// the response meant to remove: a ball settling on the ground gained energy. So a particle that
/// the plane pass left on a plane is held there by the next step's solve instead: its velocity
/// along the plane's normal is prescribed (what ends the step at the skin), and the solve moves the
/// rest of its body with it. A hold whose plane pulled the particle towards it lets go at the next
/// step.
///
/// A particle that meets a plane during a step is caught after the step's solve, at the end the
/// solve predicts, and held in the solve's next round (catchInRound), as the contact springs'
/// active set changes between rounds. Caught after the step instead, it made the whole step be
/// taken again, every round of its springs included: on three steps in four of the two-layer pile
/// and of figure 7, for 25% and 16% of their CG iterations. So that the step need not be solved
/// again for the particles that creep onto the plane at the edge of a resting contact, a particle
/// whose last change of velocity, repeated, takes it into the skin is held from the start; where
/// the plane then pulled it, the guess was wrong, and it is let go in the next round. What the
/// rounds leave (the step's last velocity change, friction and momentum, differs from the
/// prediction) is caught after the step, which is then taken again.
///
/// Holding soft–soft contacts the same way was tried: the struck triangle moves in the same solve,
/// which a one-sided hold cannot see, so held particles crossed again every substep and figure 7's
/// intersecting pairs grew (bench/results/contacts.md).

#include <cstdint>
#include <span>
#include <vector>

#include "core/dynamics/implicit_euler.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

class ContactHolds {
 public:
  explicit ContactHolds(const SceneTopology& topology);

  /// Per particle, the plane the plane pass left it on (kNoPlane): what resolvePlaneContacts
  /// records into. Empty when the scene has no planes.
  std::span<std::int32_t> touchedPlane() { return touchedPlane_; }
  std::span<const std::int32_t> touchedPlane() const { return touchedPlane_; }

  /// Before an implicit step of `dt`: holds every particle left on a plane in `solver`, and, with
  /// `expect`, every free one the step is expected to bring within the skin of one: its velocity
  /// changed by the solver's last Δv (its warm start) ends the step there. Taken again
  /// (catchImpacts()), a step holds those expected before whose plane pushed them, without
  /// expecting more.
  void holdFor(ImplicitEuler& solver, const SimulationState& state, Scalar dt, bool expect);

  /// After an implicit step, before its plane pass: marks every particle the step left on or
  /// behind a plane that no hold held. Returns how many: when any, the caller takes the step
  /// again from its start with those held too (holdFor), so that a particle meeting the ground is
  /// stopped within the solve, which moves its neighbours with it, instead of being projected
  /// back after it (a vertical sheet landing on its edge gained 0.5 J that way).
  std::size_t catchImpacts(const SimulationState& state);
  /// Within a step's rounds, after a solve: holds every particle the solve's Δv would leave on or
  /// behind a plane, and lets go of those held as expected whose plane pulled them. Returns how
  /// many changed.
  std::size_t catchInRound(ImplicitEuler& solver, const SimulationState& state, Scalar dt);

  /// After an implicit step, after catchImpacts(): lets go of the particles held because they were
  /// expected to meet a plane whose plane pulled them (they were leaving it), and returns how many.
  /// When any, the caller takes the step again without them: a hold that pulls stores the
  /// difference in the springs, which at one substep a frame flattened falling balls by 45%.
  std::size_t dropWrongExpectations(const ImplicitEuler& solver);

  /// After the step and its plane pass: lets go of the particles the plane pulled on, unless the
  /// plane pass caught them again, and keeps holding those it pushed, which the step left at the
  /// skin, where the plane pass does not see them. Returns how many it kept that way: plane
  /// contacts the plane pass did not count.
  std::size_t update(const ImplicitEuler& solver);

 private:
  /// The first plane whose skin `point` is within or behind, or kNoPlane.
  std::int32_t firstTouchedPlane(const Vec3& point) const;
  /// The speed along `plane`'s normal that takes a particle at `position` to its skin in `dt`.
  Scalar skinSpeed(std::int32_t plane, const Vec3& position, Scalar dt) const;
  /// Ends particle i's hold on its plane when it was held as expected and the plane pulled it.
  bool letGoIfWrong(const ImplicitEuler& solver, Index i);

  const SceneTopology& topology_;
  std::vector<std::int32_t> touchedPlane_;
  std::vector<std::int32_t> heldPlane_;  ///< per particle: the plane of its hold in this step
  std::vector<std::uint8_t> expected_;   ///< per particle: held in this step as expected
};

}  // namespace softbake
