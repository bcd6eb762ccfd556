#pragma once
/// Everything needed to start a simulation, in memory and independent of any file format.
/// importers/ fills it from a scene file; tests and the built-in scenes fill it directly.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/collision/broad_phase.hpp"

#include "core/dynamics/material.hpp"
#include "core/mesh/triangle_mesh.hpp"

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
  /// Collide the body with itself. Unset: on, open or closed (a flag folds onto itself, and a
  /// closed body pressed into the ground or squeezed in a pile creases into itself).
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

/// A static triangle mesh (the sphere of the paper's figure 6). It never moves.
struct StaticMeshCollider {
  std::string name;
  TriangleMesh mesh;  ///< world space
  Scalar restitution = 0.2f;
  Scalar friction = 0.3f;
};

/// How the collision response of Mesit & Guha §2.4 acts.
enum class ResponseMode {
  TwoSided,  ///< both sides of a soft–soft contact move, weighted by mass: momentum is conserved
  Paper,     ///< only the particle that crossed is moved, as the paper does
  None,      ///< detection only: contacts are found and recorded, nothing moves (figure 5b)
};

/// Every mode, in the order the command line and the scene format list them.
inline constexpr ResponseMode kResponseModes[] = {ResponseMode::TwoSided, ResponseMode::Paper,
                                                  ResponseMode::None};

/// "two-sided", "paper", "none".
std::string_view responseModeName(ResponseMode mode);
/// The names of kResponseModes, in order.
std::vector<std::string> responseModeNames();
/// The mode a name gives, or false for an unknown name.
bool parseResponseMode(std::string_view name, ResponseMode& mode);

/// What the collision stage does with surfaces that intersect at the start
/// (core/collision/initial_overlap.hpp).
enum class InitialOverlapMode {
  /// The triangle pairs that intersect at the start are left alone until they are found apart;
  /// every other pair collides from the first step (Vellum's and Marvelous Designer's way)
  SetAside,
  Separate,  ///< two bodies moved apart as wholes over the first frames
  Ignore,    ///< surfaces that intersect at the start never collide with each other (glued parts)
};
inline constexpr InitialOverlapMode kInitialOverlapModes[] = {
    InitialOverlapMode::SetAside, InitialOverlapMode::Separate, InitialOverlapMode::Ignore};

/// How a substep advances velocities and positions (core/dynamics/).
enum class IntegratorKind {
  Explicit,  ///< the paper's explicit (symplectic) Euler, §1.2: stable below a time-step bound
  Implicit,  ///< backward Euler, linearised once (Baraff & Witkin 1998): stable at any step
  Xpbd,      ///< XPBD with small steps (Macklin et al. 2016, 2019): stable at any step
};

/// Every kind, in the order the command line and the scene format list them.
inline constexpr IntegratorKind kIntegratorKinds[] = {
    IntegratorKind::Explicit, IntegratorKind::Implicit, IntegratorKind::Xpbd};

/// "explicit", "implicit", "xpbd".
std::string_view integratorName(IntegratorKind kind);
/// The names of kIntegratorKinds, in order.
std::vector<std::string> integratorNames();
/// The kind a name gives, or false for an unknown name.
bool parseIntegrator(std::string_view name, IntegratorKind& kind);

struct CollisionSettings {
  /// The fastest correct broad phase, measured (bench/results/README.md): the AABB tree. The
  /// paper's subdivided boxes and box hash remain one key away ("sbhash"), with identical results.
  BroadPhaseKind broadPhase = BroadPhaseKind::Bvh;
  int subdivisionLevels = 3;  ///< level L of the subdivided boxes (sbhash): 2^L leaves per axis
  ResponseMode response = ResponseMode::TwoSided;
  Scalar restitution = 0.2f;  ///< between soft bodies; static colliders carry their own
  Scalar friction = 0.3f;
  /// Reuse the broad phase's pairs while every triangle stays within a margin of where it was
  /// (core/collision/pair_cache.hpp): identical results, the broad phase once every few dozen
  /// steps. Off runs the broad phase every step, to compare broad phases themselves.
  bool pairCache = true;
  InitialOverlapMode initialOverlap = InitialOverlapMode::SetAside;
  /// After the paper's response, continuous tests keep every triangle from passing through another
  /// during the substep (core/collision/failsafe.hpp). Off, or under response "none": the
  /// paper's pipeline alone.
  bool failsafe = true;
};

struct SimulationSettings {
  double fps = 24;
  int frames = 240;
  /// Backward Euler, stable at any step (the default: fewest steps per frame on every example,
  /// bench/results/integrators.md); "explicit" is the paper's explicit Euler, as the figures
  /// were made; "xpbd" the position-based candidate.
  IntegratorKind integrator = IntegratorKind::Implicit;
  /// Substeps per frame; 0 chooses them: for the explicit integrator from its stability bound,
  /// for the others from contact accuracy (core/dynamics/stability.hpp).
  int substeps = 0;
  Vec3 gravity = Vec3(0, Scalar(-9.81), 0);  ///< m/s²
  /// Speed above which a particle is taken to have blown up, in scene units per second.
  Scalar maxSpeed = 1000;
  /// Distance particles are left outside a surface after a collision response, scene units.
  Scalar skin = Scalar(1e-3);
  std::string units = "m";  ///< recorded in the outputs; the simulation is unit-agnostic
  CollisionSettings collisions;
};

struct SceneSetup {
  std::string name = "scene";
  SimulationSettings settings;
  std::vector<BodySetup> bodies;
  std::vector<PlaneCollider> planes;
  std::vector<StaticMeshCollider> staticMeshes;
};

}  // namespace softbake
