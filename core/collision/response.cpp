#include "core/collision/response.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/collision/continuous_collision.hpp"
#include "core/collision/geometry.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

namespace {

/// What the response reads (the topology) and moves (the state).
struct ResponseScene {
  const SceneTopology& topology;
  SimulationState& state;
  const CollisionGeometry& geometry;
  const Scalar skin =
      topology.settings.skin;  ///< left between a responding particle and the surface
  std::span<const std::pair<Index, Index>> leaveAlone;   ///< surface pairs, sorted
  InsideTest inside = InsideTest::StruckFace;            ///< what counts an edge end inside
  std::span<const std::pair<Index, Index>> overlapping;  ///< surface pairs, sorted
  const Vec3& vertex(Index v) const { return geometry.vertex(state.position, v); }
  bool leftAlone(Index surfaceA, Index surfaceB) const {
    return holdsSurfacePair(leaveAlone, surfaceA, surfaceB);
  }
};

/// Whether the edge pushes leave `edge` alone: tangled, or between surfaces that overlapped at the
/// scene's start.
bool leftAlone(const ResponseScene& scene, const EdgeContact& edge) {
  const Index a = scene.geometry.triangleSurface[edge.edgeTriangle];
  const Index b = scene.geometry.triangleSurface[edge.triangle];
  return scene.leftAlone(a, b) || holdsSurfacePair(scene.overlapping, a, b);
}

/// One side of a contact as weighted vertices: the struck surface's (up to two triangles'
/// corners), or the moving one's (a particle, or the two ends of an edge).
struct StruckPoint {
  std::array<Index, 6> vertex{};
  std::array<Scalar, 6> weight{};
  int count = 0;
  void add(const Triangle& t, const Vec3& barycentric, Scalar share) {
    for (int k = 0; k < 3; ++k) add(t[k], share * barycentric[k]);
  }
  void add(Index v, Scalar w) {
    vertex[count] = v;
    weight[count++] = w;
  }
};

Scalar inverseMass(const ResponseScene& scene, Index v) {
  return v < scene.geometry.particleCount ? scene.topology.inverseMass[v] : Scalar(0);
}

Vec3 velocity(const ResponseScene& scene, Index v) {
  return v < scene.geometry.particleCount ? scene.state.velocity[v] : Vec3::Zero();
}

Vec3 unitNormal(const ResponseScene& scene, Index triangle) {
  const Triangle& t = scene.geometry.triangleVertices[triangle];
  const Vec3 &a = scene.vertex(t[0]), &b = scene.vertex(t[1]), &c = scene.vertex(t[2]);
  return (b - a).cross(c - a).normalized();
}

/// Moves the point `mover` by `shift` relative to the struck point and sets their relative velocity
/// from `normal`, splitting both between the two sides by inverse mass: vertex i of the mover
/// takes wᵢ·invAᵢ/k of each change and corner j of the struck side −wⱼ·invBⱼ/k, with
/// k = Σ wᵢ²·invAᵢ + Σ wⱼ²·invBⱼ, which gives the whole change at the contact point and leaves the
/// total momentum unchanged (k is raised where a share would pass 1, below). In the paper's mode
/// the struck side has no share (invB = 0). Returns false, with nothing to move, when neither side
/// can move.
bool computeCorrection(const ResponseScene& scene, const StruckPoint& mover,
                       const StruckPoint& struck, const Vec3& shift, const Vec3& normal,
                       Scalar restitution, Scalar friction, ResponseMode mode,
                       Correction& correction) {
  correction.count = 0;
  std::array<Scalar, 6> invA{}, invB{};
  Scalar k = 0;
  Vec3 moverVelocity = Vec3::Zero();
  for (int i = 0; i < mover.count; ++i) {
    invA[i] = inverseMass(scene, mover.vertex[i]);
    k += mover.weight[i] * mover.weight[i] * invA[i];
    moverVelocity += mover.weight[i] * velocity(scene, mover.vertex[i]);
  }
  for (int i = 0; i < struck.count; ++i) {
    invB[i] = mode == ResponseMode::Paper ? Scalar(0) : inverseMass(scene, struck.vertex[i]);
    k += struck.weight[i] * struck.weight[i] * invB[i];
  }
  if (!(k > 0)) return false;

  Vec3 surfaceVelocity = Vec3::Zero();
  for (int i = 0; i < struck.count; ++i)
    surfaceVelocity += struck.weight[i] * velocity(scene, struck.vertex[i]);
  const Vec3 relative = moverVelocity - surfaceVelocity;
  const Scalar normalSpeed = relative.dot(normal);
  Vec3 velocityChange = Vec3::Zero();
  if (normalSpeed < 0) {
    const Vec3 tangential = relative - normalSpeed * normal;
    const Scalar tangentialSpeed = tangential.norm();
    // Coulomb: the normal impulse (1+e)·|v_n| bounds how much tangential speed friction removes.
    const Scalar slowdown = friction * (1 + restitution) * -normalSpeed;
    const Scalar keep = tangentialSpeed > slowdown ? 1 - slowdown / tangentialSpeed : Scalar(0);
    velocityChange = keep * tangential - restitution * normalSpeed * normal - relative;
  }

  // A light corner beside heavy ones (or near the contact point, where the others' weights are
  // small) takes a share up to 1/w of the change: a struck corner of the engine's light parts was
  // moved 1.7 times a 0.3 m shift. Scaled as a whole so that no vertex moves further than the
  // change itself, the split still conserves momentum; the contact point then moves less, and
  // the next pass, or the failsafe, does the rest.
  Scalar largest = 0;
  for (int i = 0; i < mover.count; ++i) largest = std::max(largest, mover.weight[i] * invA[i]);
  for (int i = 0; i < struck.count; ++i) largest = std::max(largest, struck.weight[i] * invB[i]);
  k = std::max(k, largest);
  for (int i = 0; i < mover.count; ++i) {
    if (invA[i] == 0) continue;
    const Scalar share = mover.weight[i] * invA[i] / k;
    correction.add(mover.vertex[i], share * shift, share * velocityChange);
  }
  for (int i = 0; i < struck.count; ++i) {
    if (invB[i] == 0) continue;
    const Scalar share = struck.weight[i] * invB[i] / k;
    correction.add(struck.vertex[i], -share * shift, -share * velocityChange);
  }
  return true;
}

/// The same for particle `p`.
bool computeCorrection(const ResponseScene& scene, Index p, const StruckPoint& struck,
                       const Vec3& shift, const Vec3& normal, Scalar restitution, Scalar friction,
                       ResponseMode mode, Correction& correction) {
  StruckPoint mover;
  mover.add(p, 1);
  return computeCorrection(scene, mover, struck, shift, normal, restitution, friction, mode,
                           correction);
}

/// The longest edge of the triangles around particle p: the scale of its own springs.
Scalar longestEdgeAround(const ResponseScene& scene, Index p) {
  Scalar longest = 0;
  for (Index t : scene.geometry.trianglesAround(p)) {
    const Triangle& corners = scene.geometry.triangleVertices[t];
    for (int k = 0; k < 3; ++k)
      longest = std::max(
          longest, (scene.vertex(corners[(k + 1) % 3]) - scene.vertex(corners[k])).squaredNorm());
  }
  return std::sqrt(longest);
}

/// `shift` cut to at most `reach` long, keeping its part along the unit `normal` first.
Vec3 boundedShift(const Vec3& shift, const Vec3& normal, Scalar reach) {
  if (!(shift.squaredNorm() > reach * reach)) return shift;
  const Scalar out = shift.dot(normal);
  const Scalar kept = std::clamp(out, -reach, reach);
  const Vec3 along = shift - out * normal;
  const Scalar room = std::sqrt(std::max(Scalar(0), reach * reach - kept * kept));
  const Scalar length = along.norm();
  return kept * normal + (length > room ? room / length : Scalar(1)) * along;
}

/// Applies a correction at once.
bool correct(const ResponseScene& scene, Index p, const StruckPoint& struck, const Vec3& shift,
             const Vec3& normal, Scalar restitution, Scalar friction, ResponseMode mode) {
  Correction correction;
  if (!computeCorrection(scene, p, struck, shift, normal, restitution, friction, mode, correction))
    return false;
  for (int i = 0; i < correction.count; ++i) {
    scene.state.position[correction.vertex[i]] += correction.shift[i];
    scene.state.velocity[correction.vertex[i]] += correction.velocityChange[i];
  }
  return true;
}

/// The point of the line where the planes (n1, p1) and (n2, p2) meet that is closest to `x`.
/// The normals are unit and between 30° and 150° apart (kCornerCosine), so the system is well
/// posed.
Vec3 closestPointOnPlaneIntersection(const Vec3& n1, const Vec3& p1, const Vec3& n2, const Vec3& p2,
                                     const Vec3& x) {
  const Vec3d a = n1.cast<double>(), b = n2.cast<double>();
  const double d1 = a.dot(p1.cast<double>()), d2 = b.dot(p2.cast<double>());
  const double c = a.dot(b);
  const double determinant = 1 - c * c;
  const Vec3d onLine = ((d1 - d2 * c) * a + (d2 - d1 * c) * b) / determinant;
  const Vec3d direction = a.cross(b).normalized();
  const Vec3d closest = onLine + (x.cast<double>() - onLine).dot(direction) * direction;
  return closest.cast<Scalar>();
}

}  // namespace

namespace {

/// Case 1 or case 2 per particle, from its hits (sorted by particle, earliest crossing first).
void respondToParticleContacts(const ResponseScene& scene, const std::vector<ParticleContact>& hits,
                               ResponseMode mode, std::vector<Contact>& contacts,
                               CollisionResponseStats& stats) {
  const CollisionGeometry& geometry = scene.geometry;
  const bool respond = mode != ResponseMode::None;
  for (std::size_t begin = 0; begin < hits.size();) {
    const Index p = hits[begin].particle;
    std::size_t end = begin + 1;
    while (end < hits.size() && hits[end].particle == p) ++end;
    const ParticleContact& first = hits[begin];  // the earliest crossing: closest to the particle
    const ParticleContact* second = nullptr;
    for (std::size_t i = begin + 1; i < end && !second; ++i)
      if (std::abs(hits[i].normal.dot(first.normal)) < kCornerCosine) second = &hits[i];
    begin = end;

    const Index surfaceB = geometry.triangleSurface[first.triangle];
    Contact contact;
    contact.surfaceA = scene.topology.particleBody[p];
    contact.surfaceB = surfaceB;
    contact.triangleB = first.triangle;
    contact.particle = p;
    StruckPoint struck;
    if (second) {
      contact.kind = ContactKind::Corner;
      contact.normal = (first.normal + second->normal).normalized();
      contact.position =
          closestPointOnPlaneIntersection(first.normal, first.hit.point, second->normal,
                                          second->hit.point, scene.state.position[p]);
      struck.add(geometry.triangleVertices[first.triangle], first.hit.barycentric, Scalar(0.5));
      struck.add(geometry.triangleVertices[second->triangle], second->hit.barycentric, Scalar(0.5));
      ++stats.cornerResponses;
    } else {
      contact.kind = ContactKind::ParticleTriangle;
      contact.normal = first.normal;
      contact.position = first.hit.point;
      struck.add(geometry.triangleVertices[first.triangle], first.hit.barycentric, 1);
      ++stats.particleResponses;
    }
    const Vec3 target = contact.position + scene.skin * contact.normal;
    contacts.push_back(contact);
    if (!respond || scene.leftAlone(contact.surfaceA, surfaceB)) continue;
    // The crossing lies on the particle's path relative to the triangle, which a triangle thrown
    // or turned within the substep makes long: in the 1 m engine of assimp's corpus, targets lay
    // 0.3 m from their particle. Moved that far, its springs hold the throw as energy. So a
    // particle moves at most one of its own edges: out along the normal first, since that is
    // what parts it from the surface, and along the surface with what is left of the edge.
    const Vec3 shift =
        boundedShift(target - scene.state.position[p], contact.normal, longestEdgeAround(scene, p));
    correct(scene, p, struck, shift, contact.normal, geometry.restitution[surfaceB],
            geometry.friction[surfaceB], mode);
  }
}

/// Records every edge contact.
void recordEdgeContacts(const ResponseScene& scene, const std::vector<EdgeContact>& edges,
                        std::vector<Contact>& contacts) {
  const CollisionGeometry& geometry = scene.geometry;
  for (const EdgeContact& edge : edges) {
    Contact contact;
    contact.kind = ContactKind::EdgeTriangle;
    contact.position = edge.hit.point;
    contact.normal = unitNormal(scene, edge.triangle);
    contact.surfaceA = geometry.triangleSurface[edge.edgeTriangle];
    contact.surfaceB = geometry.triangleSurface[edge.triangle];
    contact.triangleA = edge.edgeTriangle;
    contact.triangleB = edge.triangle;
    contacts.push_back(contact);
  }
}

/// Gathers the push of an edge that cuts a rim (findRimCrossing) apart from the rim, by what brings
/// them the skin apart, at most kMaxEdgePush of the edge's length. Returns whether it gathered one.
bool pushRimCrossing(const ResponseScene& scene, const EdgeContact& edge, ResponseMode mode,
                     Correction& correction, EdgePushes& gathered) {
  const std::optional<RimCrossing> rim =
      findRimCrossing(scene.geometry, scene.state.position, edge);
  if (!rim || rim->separation >= scene.skin) return false;
  const Scalar edgeLength = (scene.vertex(rim->edge[1]) - scene.vertex(rim->edge[0])).norm();
  StruckPoint mover, struck;
  mover.add(rim->edge[0], 1 - rim->along);
  mover.add(rim->edge[1], rim->along);
  struck.add(rim->rim[0], 1 - rim->alongRim);
  struck.add(rim->rim[1], rim->alongRim);
  const Index surfaceB = scene.geometry.triangleSurface[edge.triangle];
  if (!computeCorrection(
          scene, mover, struck,
          std::min(scene.skin - rim->separation, kMaxEdgePush * edgeLength) * rim->normal,
          rim->normal, scene.geometry.restitution[surfaceB], scene.geometry.friction[surfaceB],
          mode, correction))
    return false;
  gathered.add(correction);
  return true;
}

/// One pass of edge pushes: each edge end that lies inside a closed surface is pushed back out.
/// Every push of the pass is measured on the positions as the pass found them and gathered first,
/// then all are applied, scaled (EdgePushes). Returns the pushes gathered.
std::size_t pushEdgeEndsOut(const ResponseScene& scene, const std::vector<EdgeContact>& edges,
                            ResponseMode mode, EdgePushes& gathered) {
  const CollisionGeometry& geometry = scene.geometry;
  std::size_t pushes = 0;
  Correction correction;
  for (const EdgeContact& edge : edges) {
    const Index surfaceB = geometry.triangleSurface[edge.triangle];
    if (leftAlone(scene, edge)) continue;
    // The end of the edge inside a closed surface: back out through the face's plane, lifted by
    // the skin. Depth is measured on the positions as the pass found them (after the particle
    // responses and the earlier passes), so an end that an earlier pass pushed out is left alone.
    const EdgeEndsInside inside =
        findEdgeEndsInside(geometry, scene.state.position, edge, scene.inside);
    if (inside.count == 0) {
      if (scene.inside == InsideTest::NearestFace &&
          pushRimCrossing(scene, edge, mode, correction, gathered))
        ++pushes;
      continue;
    }
    StruckPoint struck;
    struck.add(geometry.triangleVertices[edge.triangle], edge.hit.barycentric, 1);
    const Triangle& edgeTriangle = geometry.triangleVertices[edge.edgeTriangle];
    const Scalar edgeLength =
        (scene.vertex(edgeTriangle[(edge.edge + 1) % 3]) - scene.vertex(edgeTriangle[edge.edge]))
            .norm();
    const Scalar maxPush = kMaxEdgePush * edgeLength;
    for (int k = 0; k < inside.count; ++k) {
      if (!computeCorrection(scene, inside.end[k], struck,
                             std::min(scene.skin + inside.depth[k], maxPush) * inside.normal,
                             inside.normal, geometry.restitution[surfaceB],
                             geometry.friction[surfaceB], mode, correction))
        continue;
      ++pushes;
      gathered.add(correction);
    }
  }
  gathered.apply(scene.state);
  return pushes;
}

}  // namespace

EdgePushes::EdgePushes(std::size_t particles) : count_(particles, 0) {}

void EdgePushes::add(const Correction& correction) {
  corrections_.push_back(correction);
  for (int i = 0; i < correction.count; ++i) ++count_[correction.vertex[i]];
}

void EdgePushes::apply(SimulationState& state) {
  for (const Correction& correction : corrections_) {
    std::uint32_t most = 1;
    for (int i = 0; i < correction.count; ++i) most = std::max(most, count_[correction.vertex[i]]);
    const Scalar share = Scalar(1) / Scalar(most);
    for (int i = 0; i < correction.count; ++i) {
      state.position[correction.vertex[i]] += share * correction.shift[i];
      state.velocity[correction.vertex[i]] += share * correction.velocityChange[i];
    }
  }
  for (const Correction& correction : corrections_)
    for (int i = 0; i < correction.count; ++i) count_[correction.vertex[i]] = 0;
  corrections_.clear();
}

EdgeEndsInside findEdgeEndsInside(const CollisionGeometry& geometry,
                                  std::span<const Vec3> positions, const EdgeContact& edge,
                                  InsideTest test) {
  EdgeEndsInside inside;
  if (!geometry.surfaceClosed[geometry.triangleSurface[edge.triangle]]) return inside;
  const TriangleCorners face = geometry.corners(positions, edge.triangle);
  inside.normal = (face[1] - face[0]).cross(face[2] - face[0]).normalized();
  inside.facePoint = edge.hit.barycentric[0] * face[0] + edge.hit.barycentric[1] * face[1] +
                     edge.hit.barycentric[2] * face[2];
  Scalar faceSize = 0;
  for (int k = 0; k < 3; ++k) faceSize = std::max(faceSize, (face[(k + 1) % 3] - face[k]).norm());
  const Triangle& edgeTriangle = geometry.triangleVertices[edge.edgeTriangle];
  for (Index end : {edgeTriangle[edge.edge], edgeTriangle[(edge.edge + 1) % 3]}) {
    const Vec3& at = geometry.vertex(positions, end);
    const Vec3 offset = at - inside.facePoint;
    const Scalar depth = -inside.normal.dot(offset);
    if (depth <= 0 || offset.norm() > faceSize) continue;
    if (test == InsideTest::NearestFace &&
        !behindNearestFace(geometry, positions, edge.triangle, at))
      continue;
    inside.end[inside.count] = end;
    inside.depth[inside.count++] = depth;
  }
  return inside;
}

std::optional<RimCrossing> findRimCrossing(const CollisionGeometry& geometry,
                                           std::span<const Vec3> positions,
                                           const EdgeContact& edge) {
  const EdgeEndsInside paper = findEdgeEndsInside(geometry, positions, edge);
  if (paper.count != 1) return std::nullopt;
  const Triangle& face = geometry.triangleVertices[edge.triangle];
  const TriangleCorners corners = geometry.corners(positions, edge.triangle);
  const Vec3d a = corners[0].cast<double>(), b = corners[1].cast<double>(),
              c = corners[2].cast<double>();
  const Vec3d end = geometry.vertex(positions, paper.end[0]).cast<double>();
  // The rim is the face's edge its foot lies furthest past: opposite the most negative of the
  // foot's barycentric coordinates.
  const std::optional<std::array<double, 3>> foot = footBarycentric(a, b, c, end);
  if (!foot) return std::nullopt;
  const int opposite = int(std::min_element(foot->begin(), foot->end()) - foot->begin());
  if (!((*foot)[opposite] < 0)) return std::nullopt;
  const Index r0 = face[(opposite + 1) % 3], r1 = face[(opposite + 2) % 3];
  // The face across the rim.
  Index across = kNoIndex;
  for (Index t : geometry.trianglesAround(r0))
    if (t != edge.triangle && hasVertex(geometry.triangleVertices[t], r1)) {
      across = t;
      break;
    }
  if (across == kNoIndex) return std::nullopt;
  const Vec3d acrossNormal = [&] {
    const TriangleCorners o = geometry.corners(positions, across);
    return Vec3d((o[1] - o[0]).cross(o[2] - o[0]).cast<double>().normalized());
  }();
  const Vec3d outward = (b - a).cross(c - a).normalized() + acrossNormal;

  RimCrossing crossing;
  const Triangle& edgeTriangle = geometry.triangleVertices[edge.edgeTriangle];
  crossing.edge = {edgeTriangle[edge.edge], edgeTriangle[(edge.edge + 1) % 3]};
  crossing.rim = {r0, r1};
  const Vec3d e0 = geometry.vertex(positions, crossing.edge[0]).cast<double>();
  const Vec3d e1 = geometry.vertex(positions, crossing.edge[1]).cast<double>();
  const Vec3d q0 = geometry.vertex(positions, r0).cast<double>();
  const Vec3d q1 = geometry.vertex(positions, r1).cast<double>();
  Vec3d normal = (e1 - e0).cross(q1 - q0);
  // An edge along the rim has no common perpendicular with it (within about 6°).
  if (!(normal.squaredNorm() > 0.01 * (e1 - e0).squaredNorm() * (q1 - q0).squaredNorm()))
    return std::nullopt;
  normal.normalize();
  if (normal.dot(outward) < 0) normal = -normal;
  const std::array<double, 2> where = closestSegmentParameters(e0, e1, q0, q1);
  crossing.along = Scalar(where[0]);
  crossing.alongRim = Scalar(where[1]);
  crossing.normal = normal.cast<Scalar>();
  crossing.separation =
      Scalar(normal.dot((e0 + where[0] * (e1 - e0)) - (q0 + where[1] * (q1 - q0))));
  return crossing;
}

bool behindNearestFace(const CollisionGeometry& geometry, std::span<const Vec3> positions,
                       Index triangle, const Vec3& point) {
  const Vec3d p = point.cast<double>();
  double least = std::numeric_limits<double>::infinity();
  Vec3d nearestCorner = Vec3d::Zero(), nearestNormal = Vec3d::Zero();
  const auto consider = [&](Index t) {
    const TriangleCorners c = geometry.corners(positions, t);
    const Vec3d a = c[0].cast<double>(), b = c[1].cast<double>(), d = c[2].cast<double>();
    const Vec3d normal = (b - a).cross(d - a);
    if (normal.squaredNorm() == 0) return;  // a collapsed triangle has no side
    const double distance = pointTriangleDistance(p, a, b, d);
    if (distance >= least) return;
    least = distance;
    nearestCorner = a;
    nearestNormal = normal;
  };
  consider(triangle);
  for (Index v : geometry.triangleVertices[triangle])
    for (Index t : geometry.trianglesAround(v)) consider(t);
  return nearestNormal.dot(p - nearestCorner) < 0;
}

CollisionResponseStats respondToCollisions(const SceneTopology& topology,
                                           const CollisionGeometry& geometry,
                                           const CollisionDetector& detector, ResponseMode mode,
                                           SimulationState& state, std::vector<Contact>& contacts,
                                           EdgePushes& edgePushes,
                                           std::span<const std::pair<Index, Index>> leaveAlone,
                                           InsideTest inside,
                                           std::span<const std::pair<Index, Index>> overlapping) {
  const ResponseScene scene{topology,   state,  geometry,   topology.settings.skin,
                            leaveAlone, inside, overlapping};
  CollisionResponseStats stats;
  contacts.clear();
  respondToParticleContacts(scene, detector.particleContacts(), mode, contacts, stats);
  recordEdgeContacts(scene, detector.edgeContacts(), contacts);
  if (mode != ResponseMode::None)
    for (int pass = 0; pass < kEdgePushPasses; ++pass)
      stats.edgePushes += pushEdgeEndsOut(scene, detector.edgeContacts(), mode, edgePushes);
  return stats;
}

}  // namespace softbake
