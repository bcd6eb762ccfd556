#pragma once
/// A contact found by the collision pipeline: where two surfaces met during a substep.

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

#include "core/scene/scene_topology.hpp"
#include "core/types.hpp"

namespace softbake {

constexpr Index kNoIndex = std::numeric_limits<Index>::max();

enum class ContactKind : std::uint8_t {
  EdgeTriangle,      ///< an edge of surface A crosses a triangle of surface B (the paper's §2.3)
  ParticleTriangle,  ///< a particle of A crossed a triangle of B during the step: case 1 of §2.4
  Corner,            ///< a particle of A crossed two triangles of B at an angle: case 2 of §2.4
  Plane,             ///< a particle of body A touches ground plane B (an index into the planes)
  /// A particle of A held off a triangle of B within the step's solve, at the end of the substep
  /// (core/dynamics/contact_springs.hpp); for a static mesh's vertex, `particle` is kNoIndex.
  Held,
};

/// "edge-triangle", "particle-triangle", "corner", "plane", "held": the names the contact files
/// use.
constexpr std::string_view contactKindName(ContactKind kind) {
  switch (kind) {
    case ContactKind::EdgeTriangle:
      return "edge-triangle";
    case ContactKind::ParticleTriangle:
      return "particle-triangle";
    case ContactKind::Corner:
      return "corner";
    case ContactKind::Plane:
      return "plane";
    case ContactKind::Held:
      return "held";
  }
  return "edge-triangle";
}

struct Contact {
  Vec3 position = Vec3::Zero();  ///< the intersection point (the paper's grey spheres)
  Vec3 normal = Vec3::Zero();    ///< of the struck surface, pointing to where A came from
  /// Collision surfaces: bodies, then static meshes. For a plane contact, surfaceB is the plane's
  /// index in SceneTopology::planes.
  Index surfaceA = kNoIndex, surfaceB = kNoIndex;
  Index triangleA = kNoIndex;  ///< the crossing edge's triangle; kNoIndex for particle contacts
  Index triangleB = kNoIndex;  ///< the struck triangle (for a corner: the first of the two)
  Index particle = kNoIndex;   ///< the crossing particle; kNoIndex for edge contacts
  ContactKind kind = ContactKind::EdgeTriangle;
};

/// What surface A of `contact` met: a collision surface's name, or a plane's.
inline const std::string& contactPartnerName(const SceneTopology& topology,
                                             const Contact& contact) {
  return contact.kind == ContactKind::Plane ? topology.planes[contact.surfaceB].name
                                            : topology.surfaceName(contact.surfaceB);
}

}  // namespace softbake
