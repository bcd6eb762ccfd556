#pragma once
/// Response (Mesit & Guha §2.4) to what CollisionDetector found, and the contacts as data.
///
/// Case 1, one surface crossed: the particle goes back to where its motion met the surface (the
/// earliest crossing when it met several), lifted by the skin along the surface normal; the
/// normal part of its velocity relative to the surface is reflected with the restitution and the
/// tangential part slowed by Coulomb friction (restitution 0 and friction 0 are the paper's).
/// Case 2, two surfaces crossed at an angle (a crease, or where two bodies meet): the particle goes
/// to the closest point on the line where the two triangles' planes meet, lifted along the average
/// of the two normals, and its velocity is set from that average normal.
///
/// Where the paper moves only the particle, the default two-sided mode also moves the struck
/// triangle's corners the opposite way, weighted by the barycentric coordinates of the contact
/// and the masses, so a soft–soft contact conserves momentum; static colliders never move, so
/// against them both modes are the paper's. Edge contacts (an edge through a face) also push the
/// edge's end that lies inside a closed surface back out: particle segments see only what
/// crossed during this substep, edges see what is still inside from before.
///
/// Contacts are handled one after the other in the detector's sorted order: the result does not
/// depend on the number of threads.

#include <vector>

#include "core/collision/contact.hpp"
#include "core/collision/detection.hpp"
#include "core/scene/scene_setup.hpp"

namespace softbake {

struct SceneTopology;
struct SimulationState;

struct CollisionResponseStats {
  std::size_t particleResponses = 0;  ///< case 1
  std::size_t cornerResponses = 0;    ///< case 2
  std::size_t edgePushes = 0;         ///< edge ends pushed out of a closed surface
};

/// Two hits whose unit normals meet at more than this cosine's angle (30°) are two surfaces
/// (case 2). Neighbouring triangles of a smooth mesh differ by less: an icosphere of level 3 by
/// about 12°, so a particle through their shared edge stays case 1.
constexpr Scalar kCornerCosine = Scalar(0.8660254);

/// An edge end is pushed out of a face by at most this fraction of the edge's length per
/// substep. The half-space behind a face reaches beyond the body near
/// its silhouette, so an end "behind" a face may in truth be outside the body: a full push there
/// would move it, and the face with it, by up to an edge length in one substep, which springs turn
/// into an explosion. Capped, a deep penetration is undone over a few substeps instead.
constexpr Scalar kMaxEdgePush = Scalar(0.1);

/// Writes this substep's contacts to `contacts` (replacing what was there) and, unless `mode` is
/// ResponseMode::None, moves the particles and sets their velocities as described above.
CollisionResponseStats respondToCollisions(const SceneTopology& topology,
                                           const CollisionDetector& detector, ResponseMode mode,
                                           SimulationState& state, std::vector<Contact>& contacts);

}  // namespace softbake
