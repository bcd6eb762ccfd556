#include "core/collision/plane_contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>

#include "core/parallel.hpp"

namespace softbake {

namespace {

/// Returns true when the particle touches the plane (and, with `move`, was moved).
bool respondToPlane(const PlaneCollider& plane, Scalar skin, const Vec3& start, Vec3& x, Vec3& v,
                    bool move) {
  if (!touchesPlane(plane, skin, x)) return false;
  const Scalar endDistance = heightAbove(plane, x);
  if (!move) return endDistance < 0;
  const Scalar startDistance = heightAbove(plane, start);
  if (startDistance > 0 && endDistance < 0) {
    // Crossed during the step: the intersection point of the segment, as the paper does.
    const Scalar t = startDistance / (startDistance - endDistance);
    x = start + t * (x - start);
  }
  x += (skin - heightAbove(plane, x)) * plane.normal;
  const Scalar normalSpeed = plane.normal.dot(v);
  if (normalSpeed < 0) {
    const Vec3 tangential = v - normalSpeed * plane.normal;
    const Scalar tangentialSpeed = tangential.norm();
    // Coulomb: the normal impulse (1+e)·|v_n| bounds how much tangential speed friction removes.
    const Scalar slowdown = plane.friction * (1 + plane.restitution) * -normalSpeed;
    const Scalar keep = tangentialSpeed > slowdown ? 1 - slowdown / tangentialSpeed : Scalar(0);
    v = keep * tangential - plane.restitution * normalSpeed * plane.normal;
  }
  return true;
}
}  // namespace

std::size_t resolvePlaneContacts(const SceneTopology& topology, std::span<const Vec3> substepStart,
                                 SimulationState& state, bool respond,
                                 std::span<std::int32_t> touchedPlane) {
  if (topology.planes.empty()) return 0;
  const bool record = !touchedPlane.empty();
  const Scalar skin = topology.settings.skin;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, state.particleCount(), kParticleGrain), std::size_t(0),
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t moved) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          if (record) touchedPlane[i] = kNoPlane;
          if (topology.inverseMass[i] == 0) continue;
          for (std::size_t p = 0; p < topology.planes.size(); ++p) {
            const bool touched = respondToPlane(topology.planes[p], skin, substepStart[i],
                                                state.position[i], state.velocity[i], respond);
            moved += touched;
            if (record && touched && respond) touchedPlane[i] = std::int32_t(p);
          }
        }
        return moved;
      },
      std::plus<>());
}

void appendPlaneContacts(const SceneTopology& topology, const SimulationState& state, bool respond,
                         std::vector<Contact>& contacts) {
  // A relative margin: the particle was put at `skin` by one addition, so it lies within a few
  // ulps of it.
  const Scalar reach = respond ? topology.settings.skin * Scalar(1.001) : Scalar(0);
  for (std::size_t p = 0; p < topology.planes.size(); ++p) {
    const PlaneCollider& plane = topology.planes[p];
    for (std::size_t i = 0; i < state.particleCount(); ++i) {
      if (topology.inverseMass[i] == 0) continue;  // pinned: the plane pass leaves them alone
      const Vec3& x = state.position[i];
      const Scalar height = heightAbove(plane, x);
      if (height >= reach) continue;
      Contact& contact = contacts.emplace_back();
      contact.kind = ContactKind::Plane;
      contact.position = x - height * plane.normal;
      contact.normal = plane.normal;
      contact.surfaceA = topology.particleBody[i];
      contact.surfaceB = Index(p);
      contact.particle = Index(i);
    }
  }
}

}  // namespace softbake
