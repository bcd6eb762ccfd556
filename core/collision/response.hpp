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
/// edge's end that lies inside a closed surface back out (or, where neither end is inside, the
/// edge out of the corner it cuts: RimCrossing): particle segments see only what crossed during
/// this substep, edges see what is still inside from before.
///
/// The edge pushes are made in kEdgePushPasses passes. Within a pass every push is measured on the
/// same positions and gathered before any is applied; then each is scaled by 1/n, n the most pushes
/// of the pass that name any one of its particles (as the pushed end or a corner of the struck
/// face). So no particle moves farther than its largest single push, and each push still conserves
/// momentum. Applied one after the other, each measured on geometry the previous ones had moved,
/// the pushes compounded: in the figure 7 scene a stiff ball pressing into a jelly one takes
/// hundreds of edge pushes per substep, a particle could move many times the cap in one substep,
/// the springs stored that as energy, and the run blew up at frame 13 under every integrator. The
/// second pass measures again what the first, scaled down, left inside.
///
/// Between two surfaces that overlapped where the scene started (initial_overlap "set_aside"),
/// edges are not pushed: an edge of one part inside the other lies there by design, and as the
/// parts deform their overlap slides onto edges whose triangles did not intersect at the start.
/// Pushing those out fought the overlap's springs in every substep: assimp's regr01.obj (55 nested
/// parts) at rest took 90 J a frame from the pushes and gave it back to the integrator, its energy
/// crept up by 31 J over 30 frames (bench/results/assemblies.md). Particle segments there still
/// respond to what crossed in the substep, and the failsafe still keeps apart what did not overlap.
///
/// Contacts are handled one after the other in the detector's sorted order: the result does not
/// depend on the number of threads.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "core/collision/contact.hpp"
#include "core/collision/detection.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/types.hpp"

namespace softbake {

struct CollisionGeometry;
struct SceneTopology;
struct SimulationState;

struct CollisionResponseStats {
  std::size_t particleResponses = 0;  ///< case 1
  std::size_t cornerResponses = 0;    ///< case 2
  std::size_t edgePushes = 0;         ///< edge ends pushed out of a closed surface

  CollisionResponseStats& operator+=(const CollisionResponseStats& other) {
    particleResponses += other.particleResponses;
    cornerResponses += other.cornerResponses;
    edgePushes += other.edgePushes;
    return *this;
  }
};

/// Two hits whose unit normals meet at more than this cosine's angle (30°), and less than its
/// supplement (150°), are two surfaces meeting in a corner (case 2). Neighbouring triangles of a
/// smooth mesh differ by less: an icosphere of level 3 by about 12°, so a particle through their
/// shared edge stays case 1. Nearly opposite faces are no corner but the two sides of a gap (a
/// ball squashed flat under a load, its top face over its bottom one): their planes meet, if at
/// all, far away, and the corner point between them was not finite. The earliest hit answers.
constexpr Scalar kCornerCosine = Scalar(0.8660254);

/// An edge end is pushed out of a face by at most this fraction of the edge's length per
/// substep. The half-space behind a face reaches beyond the body near
/// its silhouette, so an end "behind" a face may in truth be outside the body: a full push there
/// would move it, and the face with it, by up to an edge length in one substep, which springs turn
/// into an explosion. Capped, a deep penetration is undone over a few substeps instead.
constexpr Scalar kMaxEdgePush = Scalar(0.1);

/// Passes of edge pushes per substep (one pass left the thrown balls of tests/core/collision_test
/// intersecting under the implicit integrator, two and three did not).
inline constexpr int kEdgePushPasses = 2;

/// What one contact does to its particle and to the struck side's corners: moves and velocity
/// changes that add up to zero momentum.
struct Correction {
  std::array<Index, 7> vertex{};
  std::array<Vec3, 7> shift{};
  std::array<Vec3, 7> velocityChange{};
  int count = 0;
  void add(Index v, const Vec3& dx, const Vec3& dv) {
    vertex[count] = v;
    shift[count] = dx;
    velocityChange[count++] = dv;
  }
};

/// The edge pushes of one substep, gathered before any is applied. Each push is then scaled by
/// 1/n, n the most pushes that name any one of its particles, so no particle moves farther than its
/// largest single push and every push still conserves momentum. Sized once for the scene's
/// particles; the list of pushes keeps its largest size, so steps allocate nothing once it is met.
class EdgePushes {
 public:
  explicit EdgePushes(std::size_t particles = 0);
  void add(const Correction& correction);
  /// Applies every push added since the last call, scaled, then forgets them.
  void apply(SimulationState& state);

 private:
  std::vector<Correction> corrections_;
  std::vector<std::uint32_t> count_;  ///< pushes per particle
};

/// The ends of an edge contact's edge that lie inside the closed surface it passes through:
/// behind the struck face's plane, and near the face (within its longest side: a long edge, a big
/// static triangle under a small body, crosses the face with its ends behind its plane but far
/// outside the body).
struct EdgeEndsInside {
  std::array<Index, 2> end{};
  std::array<Scalar, 2> depth{};  ///< how far behind the face's plane, > 0
  int count = 0;
  Vec3 normal = Vec3::Zero();     ///< the struck face's unit normal, out of its surface
  Vec3 facePoint = Vec3::Zero();  ///< where the edge passes through the face
};
/// What counts an edge end as inside the surface its edge passes through.
enum class InsideTest {
  /// Behind the struck face's plane, near the face: the paper's test.
  StruckFace,
  /// That, and behind the plane of the face nearest the end among the triangles around the struck
  /// face's corners too. Under a block resting on another, the base's particles lie centimetres
  /// behind the plane of the block's side faces, yet below its bottom face: outside. Pushed out
  /// along the side face's normal in every substep, they shoved the block sideways (18 cm in
  /// 4 s: bench/results/contacts.md).
  NearestFace,
};

/// Empty when the struck surface is open (no inside).
EdgeEndsInside findEdgeEndsInside(const CollisionGeometry& geometry,
                                  std::span<const Vec3> positions, const EdgeContact& edge,
                                  InsideTest test = InsideTest::StruckFace);

/// Whether `point` lies behind the plane of the triangle nearest it among `triangle` and the
/// triangles around its corners (the first found, `triangle` first, where several are as near).
/// Needs the geometry's vertex–triangle links (linkVertexTriangles).
bool behindNearestFace(const CollisionGeometry& geometry, std::span<const Vec3> positions,
                       Index triangle, const Vec3& point);

/// An edge that passes through a face of a closed surface and out again past one of the face's
/// edges (the rim), with neither end inside by InsideTest::NearestFace: it cuts the corner the
/// struck face makes with its neighbour across the rim. Where an end is pushed out along the struck
/// face's normal, as the paper's test does, a block resting on another was shoved sideways by the
/// base's edges under its rim; left alone, a pile's edges that cut each other's balls went to the
/// failsafe (1.9 passes a step instead of 1.3). So the edge and the rim are pushed apart along
/// their common perpendicular, out of the corner.
struct RimCrossing {
  std::array<Index, 2> edge{}, rim{};
  Scalar along = 0, alongRim = 0;  ///< where the closest points lie on the edge and on the rim
  Vec3 normal = Vec3::Zero();      ///< unit, out of the corner: towards the two faces' outside
  Scalar separation = 0;           ///< of the edge from the rim along `normal` (< 0: crossed)
};

/// The rim an edge contact's edge cuts, where it has one: an end of the edge lies behind the
/// struck face near it (the paper's test) but not behind the face nearest it, and its foot on the
/// face's plane lies outside the face, past the rim. Needs the geometry's vertex–triangle links.
std::optional<RimCrossing> findRimCrossing(const CollisionGeometry& geometry,
                                           std::span<const Vec3> positions,
                                           const EdgeContact& edge);

/// Writes this substep's contacts to `contacts` (replacing what was there) and, unless `mode` is
/// ResponseMode::None, moves the particles and sets their velocities as described above. Contacts
/// between the surface pairs of `leaveAlone` (sorted, lower surface first) are recorded but not
/// responded to: surfaces that start inside each other, which the Detangler takes apart. `inside`
/// is the edge pushes' test of an end inside a surface. The edges of the surface pairs of
/// `overlapping` (sorted, lower surface first: those that overlapped where the scene started) are
/// not pushed.
CollisionResponseStats respondToCollisions(
    const SceneTopology& topology, const CollisionGeometry& geometry,
    const CollisionDetector& detector, ResponseMode mode, SimulationState& state,
    std::vector<Contact>& contacts, EdgePushes& edgePushes,
    std::span<const std::pair<Index, Index>> leaveAlone = {},
    InsideTest inside = InsideTest::StruckFace,
    std::span<const std::pair<Index, Index>> overlapping = {});

}  // namespace softbake
