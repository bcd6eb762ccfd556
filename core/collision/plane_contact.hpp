#pragma once
/// Contact with static infinite planes (the ground): the paper's case-1 response (§2.4) for a
/// surface whose normal is the same everywhere.

#include <cstdint>
#include <span>
#include <vector>

#include "core/collision/contact.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

/// For every particle whose motion this substep (from `substepStart`) crossed a plane, or that ends
/// closer than the skin: moves it to where its segment met the plane (or projects it), lifted by
/// the skin along the normal; reflects the normal velocity with the plane's restitution and slows
/// the tangential velocity by Coulomb friction. Returns the number of particles in contact. With
/// `respond` false (detection only, the paper's figure 5b) nothing is moved. When `touchedPlane`
/// is given (one entry per particle), it receives the index of the plane each particle was moved
/// onto, or kNoPlane: the contacts the implicit integrator holds during the next step.
std::size_t resolvePlaneContacts(const SceneTopology& topology, std::span<const Vec3> substepStart,
                                 SimulationState& state, bool respond = true,
                                 std::span<std::int32_t> touchedPlane = {});

/// Appends to `contacts` one ContactKind::Plane contact for every particle in contact with a plane
/// now: at the point of the plane under it, with the plane's normal, in particle order (so the
/// list is the same for any thread count). In contact means within the skin (with `respond`: the
/// plane pass leaves a touching particle exactly at the skin, which rounding may put a hair
/// above), or behind the plane without response (what the detector found, the paper's figure 5b).
void appendPlaneContacts(const SceneTopology& topology, const SimulationState& state, bool respond,
                         std::vector<Contact>& contacts);

}  // namespace softbake
