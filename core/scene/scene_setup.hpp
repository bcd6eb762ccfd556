#pragma once
/// Everything needed to start a simulation, in memory and independent of any file format.
/// importers/ fills it from a scene file; tests and the built-in scenes fill it directly.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/triangle_mesh.hpp"
#include "core/scene/material.hpp"
#include "core/scene/settings.hpp"

namespace softbake {

/// An axis-aligned world-space box; every particle inside it at the start is pinned.
struct PinBox {
  Vec3f min = Vec3f::Zero();
  Vec3f max = Vec3f::Zero();
};

/// Particles held fixed in space for the whole simulation (flags, banners).
struct Pins {
  /// Vertices of BodySetup::mesh; each pins the particle it welds into. A scene file's
  /// `pins.indices` number the mesh file's vertices, which importers map to these.
  std::vector<Index> vertices;
  std::vector<Index> particles;  ///< welded particle indices (the `v` order of the OBJ export)
  std::vector<PinBox> boxes;
};

struct BodySetup {
  std::string name;
  TriangleMesh mesh;  ///< world space: the scene transform is already applied
  Material material;
  Scalar mass = 1;               ///< kg for the whole body, spread over particles by vertex area
  Vec3 velocity = Vec3::Zero();  ///< initial velocity of every particle, m/s
  Pins pins;
  /// Collide the body with itself. Unset: as the scene's CollisionSettings::selfCollision says
  /// (on by default, open or closed: a flag folds onto itself, and a closed body pressed into the
  /// ground or squeezed in a pile creases into itself).
  std::optional<bool> selfCollision;
};

/// An infinite static plane; particles stay on the side its normal points to.
struct PlaneCollider {
  std::string name = "ground";
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();  ///< unit length
  Scalar restitution = 0.2f;    ///< fraction of the normal speed kept on impact, 0..1
  Scalar friction = 0.3f;       ///< Coulomb coefficient on the tangential speed
};

/// No plane: what a per-particle plane index (the plane pass's, the implicit integrator's
/// holds) holds for a particle that touches none.
inline constexpr std::int32_t kNoPlane = -1;

/// How far `x` lies above `plane`, along its normal (negative behind it), in `x`'s precision.
template <class V>
typename V::Scalar heightAbove(const PlaneCollider& plane, const V& x) {
  using S = typename V::Scalar;
  return plane.normal.template cast<S>().dot(x - plane.point.template cast<S>());
}

/// Whether a particle at `x` is in contact with `plane`: closer than the skin, or behind it. The
/// one rule for the plane pass and for the implicit step's holds (core/dynamics/contact_holds).
inline bool touchesPlane(const PlaneCollider& plane, Scalar skin, const Vec3& x) {
  return heightAbove(plane, x) < skin;
}

/// A static triangle mesh (the sphere of the paper's figure 6). It never moves.
struct StaticMeshCollider {
  std::string name;
  TriangleMesh mesh;  ///< world space
  Scalar restitution = 0.2f;
  Scalar friction = 0.3f;
};

struct SceneSetup {
  std::string name = "scene";
  SimulationSettings settings;
  std::vector<BodySetup> bodies;
  std::vector<PlaneCollider> planes;
  std::vector<StaticMeshCollider> staticMeshes;
};

}  // namespace softbake
