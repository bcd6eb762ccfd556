#pragma once
/// The settings of a simulation, and the names of their choices: one list of kinds per choice,
/// one name per kind, so the scene parser, the command line, Python and the messages stay in
/// step. Plain data, seen by every layer of core and by the importers.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace softbake {

enum class BroadPhaseKind {
  Sbhash,       ///< "sbhash": the paper's multi-level subdivided boxes (§2.1) and box hash (§2.2)
  SpatialHash,  ///< Teschner et al. 2003 ("spatialhash")
  Bvh,          ///< an AABB tree, refitted each step ("bvh")
  BruteForce,   ///< every pair ("brute"): the reference
};

/// Every kind, in the order the command line and the scene format list them.
inline constexpr BroadPhaseKind kBroadPhaseKinds[] = {
    BroadPhaseKind::Sbhash, BroadPhaseKind::SpatialHash, BroadPhaseKind::Bvh,
    BroadPhaseKind::BruteForce};

/// "sbhash", "spatialhash", "bvh", "brute".
std::string_view broadPhaseName(BroadPhaseKind kind);
/// The names of kBroadPhaseKinds, in order: what the command line and the scene parser accept.
std::vector<std::string> broadPhaseNames();
/// The kind a name gives, or false for an unknown name.
bool parseBroadPhase(std::string_view name, BroadPhaseKind& kind);

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

/// "set_aside", "separate", "ignore".
std::string_view initialOverlapModeName(InitialOverlapMode mode);
std::vector<std::string> initialOverlapModeNames();
bool parseInitialOverlapMode(std::string_view name, InitialOverlapMode& mode);

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

/// How the renderer draws the bodies around the contact spheres (render/frame_renderer.hpp), a
/// setting of the scene's render section named here beside the others, so importers check it.
enum class ContactsView : std::uint8_t {
  Automatic,  ///< XRay when contact spheres are drawn and the scene has contacts between
              ///< surfaces (see contactsViewFor()), else Opaque
  XRay,       ///< bodies translucent (order-independent transparency), contacts opaque
  Opaque,     ///< bodies opaque: contacts between them are mostly hidden inside
};

/// "xray", "opaque" (and "automatic"): the names of the scene key and the command-line option.
std::string_view contactsViewName(ContactsView view);
/// The names a scene or an option can choose: "xray", "opaque" (Automatic is the default only).
std::vector<std::string> contactsViewNames();
/// The view of a name in contactsViewNames(); Automatic for any other.
ContactsView parseContactsView(std::string_view name);

struct CollisionSettings {
  /// The fastest correct broad phase, measured (bench/results/README.md): the AABB tree. The
  /// paper's subdivided boxes and box hash remain one key away ("sbhash"), with identical results.
  BroadPhaseKind broadPhase = BroadPhaseKind::Bvh;
  int subdivisionLevels = 3;  ///< level L of the subdivided boxes (sbhash): 2^L leaves per axis
  ResponseMode response = ResponseMode::TwoSided;
  Scalar restitution = 0.2f;  ///< between soft bodies; static colliders carry their own
  Scalar friction = 0.3f;
  /// Reuse the broad phase's pairs while every triangle stays within a margin of where it was
  /// (core/broad_phase/pair_cache.hpp): identical results, the broad phase once every few dozen
  /// steps. Off runs the broad phase every step, to compare broad phases themselves.
  bool pairCache = true;
  InitialOverlapMode initialOverlap = InitialOverlapMode::SetAside;
  /// After the paper's response, continuous tests keep every triangle from passing through another
  /// during the substep (core/collision/failsafe.hpp). Off, or under response "none": the
  /// paper's pipeline alone.
  bool failsafe = true;
  /// The implicit integrator keeps the contacts it finds before each step apart within its solve
  /// (core/dynamics/contact_springs.hpp), and "auto" substeps let surfaces close by a whole short
  /// edge per substep; the paper's test and response, then the failsafe, check and repair the
  /// result (4 substeps a frame where 19-23 were needed: bench/results/integrators.md). Off, or
  /// under another integrator: they alone answer every contact, after the step.
  bool contactsInStep = true;
  /// Whether a body's triangles collide with its own when its scene entry does not say
  /// (BodySetup::selfCollision): on, as a flag folds and a loaded ball creases into itself; off
  /// for a scene of bodies that cannot fold, which saves 1.1-1.5x the bake.
  bool selfCollision = true;
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

}  // namespace softbake
