#include "core/dynamics/contact_holds.hpp"

#include "core/collision/plane_contact.hpp"

namespace softbake {

ContactHolds::ContactHolds(const SceneTopology& topology)
    : topology_(topology),
      touchedPlane_(topology.planes.empty() ? 0 : topology.particleCount(), kNoPlane) {}

void ContactHolds::holdFor(ImplicitEuler& solver, const SimulationState& state, Scalar dt) const {
  solver.releaseHolds();
  const Scalar skin = topology_.settings.skin;
  for (Index i = 0; i < Index(touchedPlane_.size()); ++i) {
    if (touchedPlane_[i] == kNoPlane) continue;
    const PlaneCollider& plane = topology_.planes[touchedPlane_[i]];
    // The normal speed that ends the step at the skin, where the plane pass left it.
    const Scalar distance = plane.normal.dot(state.position[i] - plane.point);
    solver.hold(i, plane.normal, (skin - distance) / dt, plane.friction);
  }
}

void ContactHolds::update(const ImplicitEuler& solver) {
  // Every hold is a plane hold. One that pulled its particle towards the plane ends; the plane
  // pass, which ran after the step, caught the particle again only by rounding.
  for (Index i : solver.heldParticles())
    if (!(solver.holdImpulse(i) > 0)) touchedPlane_[i] = kNoPlane;
}

}  // namespace softbake
