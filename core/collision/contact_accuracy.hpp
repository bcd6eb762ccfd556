#pragma once
/// How many substeps "auto" gives the integrators that are stable at any step: few enough that a
/// frame is cheap, enough that two surfaces close on each other by only a part of the skin and a
/// short edge per substep, which the collision stages need to catch and answer each crossing.

#include <cstdint>
#include <span>
#include <vector>

#include "core/broad_phase/broad_phase.hpp"
#include "core/collision/geometry.hpp"
#include "core/scene/scene_topology.hpp"

namespace softbake {

/// The fewest and the most substeps per frame "auto" gives the integrators that are stable at any
/// step. The floor keeps the implicit integrator's numerical damping moderate where nothing is
/// about to touch: at one substep per frame a dropped rubber ball barely bounces.
inline constexpr int kMinAutoSubsteps = 4;
inline constexpr int kMaxAutoSubsteps = 64;

/// The part of (skin + short edge, contactEdgeLength()) two surfaces may close on each other in one
/// substep of an integrator that is stable at any step. Measured: at a tenth, bodies thrown at each
/// other and dropped on a static sphere stay free of intersecting triangles
/// (tests/core/collision_test); at a half they did not.
inline constexpr double kContactReachFraction = 0.1;
/// The same where the implicit solve keeps the contacts it finds before the step apart
/// (core/dynamics/contact_springs.hpp): there the collision stages no longer need to see each
/// crossing from nearby, and a substep may close surfaces by a whole short edge (plus the skin),
/// the distance over which a contact's fixed normal and foot on its triangle still hold. Measured:
/// the two-layer pile and figure 7 at 2 and 4 substeps a frame keep 0 intersecting pairs and gain
/// no energy (bench/results/integrators.md).
inline constexpr double kInStepContactReachFraction = 1.0;

/// The contact reach uses this quantile of the rest edge lengths weighted by surface area, not the
/// shortest edge: the sliver and tiny triangles of an imported CAD part, scan or character (a
/// finely modelled eye or beak, a bevel) would otherwise set the step for the whole scene. Each
/// triangle gives each of its edges a third of its area, and the short edge is the length below
/// which edges carry a twentieth of the surface: many small triangles over little of the surface
/// do not count, a finely meshed body does. On a uniform mesh, such as an icosphere, it is within
/// a few percent of the shortest edge.
inline constexpr double kShortEdgeQuantile = 0.05;

/// "auto" substeps of the implicit and XPBD integrators, which are stable at any step, so the
/// count is set by contact accuracy: over one substep, two collision surfaces that can meet within
/// the frame close on each other by at most kContactReachFraction of the skin plus the short
/// rest edge of contactEdgeLength(), so the segment tests of §2.3 see each crossing from nearby.
/// Only closing speed counts: a body's own translation does not, so a body flying alone, or bodies
/// falling side by side, take few substeps. A pair's closing speed is the difference of the two
/// surfaces' mean velocities (mass-weighted) plus each one's largest deviation from its mean
/// (deformation and spin), or the speed of the faster surface's fastest vertex where that is less
/// (the measure kContactReachFraction was calibrated with), plus what gravity adds over the frame
/// where something can hold one of them (a plane, a static surface or a pin it can reach within
/// the frame, or a surface in contact with one). Surfaces already in contact (`touching`: the
/// broad phase's triangle pairs of the latest substep) count with the speed of the fastest corner
/// of a touching triangle pair plus gravity's where they are held, and with how fast the corners
/// of the pair move apart where nothing holds them (parts of an assembly falling together). Any
/// other pair counts when its bounding boxes, each grown by how far it can travel in the frame plus
/// the skin, overlap; a self-colliding body counts against itself. Ground planes are not surfaces
/// here: their contacts are resolved exactly at any step. Re-chosen every frame; kMinAutoSubsteps
/// to kMaxAutoSubsteps. Where a collision surface is and how fast it can move, for the
/// contact-accuracy rule.
struct SurfaceMotion {
  /// Where the surface can be within the frame: its bounds grown by its travel and the skin.
  Box3 box;
  Vec3d meanVelocity = Vec3d::Zero();
  double deviation = 0;  ///< the largest |v − mean| over its vertices
  double fastest = 0;    ///< the largest |v| over its vertices
  bool moving = false;
  /// It can reach a plane or a static surface within the frame, which may stop it there.
  bool mayStop = false;
};

struct ContactAccuracy {
  int substeps = kMinAutoSubsteps;
  double closingSpeed = 0;  ///< m/s, the largest over the pairs that can meet within the frame
};
/// What contactAccuracySubsteps() works in: keeps its size, so a frame allocates nothing once the
/// first frames have grown it.
struct ContactAccuracyScratch {
  std::vector<std::uint64_t> touchingSurfaces;
  std::vector<SurfaceMotion> motion;
  std::vector<std::uint32_t> group;  ///< union-find over the surfaces in contact
  std::vector<char> held;
};
ContactAccuracy contactAccuracySubsteps(const SceneTopology& topology,
                                        const CollisionGeometry& geometry,
                                        std::span<const Vec3> positions,
                                        std::span<const Vec3> velocities,
                                        std::span<const TrianglePair> touching, double edgeLength,
                                        ContactAccuracyScratch& scratch,
                                        double reachFraction = kContactReachFraction);

/// The rest edge length that sets the contact reach: the area-weighted kShortEdgeQuantile
/// quantile of the triangles' rest edges, scene units; infinity when there is none.
double contactEdgeLength(const SceneTopology& topology);

}  // namespace softbake
