#include "core/collision/contact_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/union_find.hpp"

namespace softbake {

namespace {

SurfaceMotion softSurfaceMotion(const SceneTopology& topology, const Body& body,
                                std::span<const Vec3> positions, std::span<const Vec3> velocities) {
  SurfaceMotion motion;
  motion.moving = true;
  const Index end = body.firstParticle + body.particleCount;
  double mass = 0;
  for (Index i = body.firstParticle; i < end; ++i) {
    motion.box.extend(positions[i]);
    motion.meanVelocity += double(topology.mass[i]) * velocities[i].cast<double>();
    mass += double(topology.mass[i]);
  }
  if (mass > 0) motion.meanVelocity /= mass;
  for (Index i = body.firstParticle; i < end; ++i) {
    motion.deviation =
        std::max(motion.deviation, (velocities[i].cast<double>() - motion.meanVelocity).norm());
    motion.fastest = std::max(motion.fastest, double(velocities[i].norm()));
    // A pin holds the body against gravity, as the ground does.
    motion.mayStop = motion.mayStop || topology.inverseMass[i] == 0;
  }
  return motion;
}

SurfaceMotion staticSurfaceMotion(const CollisionGeometry& geometry,
                                  const CollisionSurface& surface) {
  SurfaceMotion motion;
  for (Index t = surface.firstTriangle; t < surface.firstTriangle + surface.triangleCount; ++t)
    for (Index v : geometry.triangleVertices[t]) motion.box.extend(geometry.vertex({}, v));
  return motion;
}

/// Whether some corner of `box` lies behind `plane`.
bool reachesBehind(const Box3& box, const PlaneCollider& plane) {
  Vec3 deepest;
  for (int axis = 0; axis < 3; ++axis)
    deepest[axis] = plane.normal[axis] > 0 ? box.min()[axis] : box.max()[axis];
  return plane.normal.dot(deepest - plane.point) < 0;
}

double travel(const SurfaceMotion& motion, double gravitySpeed) {
  return motion.moving ? motion.meanVelocity.norm() + motion.deviation + gravitySpeed : 0.0;
}

}  // namespace

ContactAccuracy contactAccuracySubsteps(const SceneTopology& topology,
                                        const CollisionGeometry& geometry,
                                        std::span<const Vec3> positions,
                                        std::span<const Vec3> velocities,
                                        std::span<const TrianglePair> touching, double edgeLength,
                                        ContactAccuracyScratch& scratch, double reachFraction) {
  const double frameTime = 1.0 / topology.settings.fps;
  const double gravitySpeed = double(topology.settings.gravity.norm()) * frameTime;
  const double skin = double(topology.settings.skin);
  const auto vertexVelocity = [&](Index v) {
    return v < geometry.particleCount ? velocities[v] : Vec3::Zero().eval();
  };

  // Each surface's motion over the frame.
  std::vector<SurfaceMotion>& motion = scratch.motion;
  motion.clear();
  for (std::size_t s = 0; s < geometry.surfaces.size(); ++s) {
    motion.push_back(s < topology.bodies.size()
                         ? softSurfaceMotion(topology, topology.bodies[s], positions, velocities)
                         : staticSurfaceMotion(geometry, geometry.surfaces[s]));
    // Grown by how far the surface can travel in the frame, plus the skin.
    const Scalar reach = Scalar(travel(motion.back(), gravitySpeed) * frameTime + skin);
    motion.back().box.min().array() -= reach;
    motion.back().box.max().array() += reach;
  }

  // Surfaces that can be stopped within the frame: by a plane, a static surface or a pin.
  for (SurfaceMotion& surface : motion) {
    if (!surface.moving) continue;
    for (const PlaneCollider& plane : topology.planes)
      surface.mayStop = surface.mayStop || reachesBehind(surface.box, plane);
    for (const SurfaceMotion& other : motion)
      surface.mayStop = surface.mayStop || (!other.moving && surface.box.intersects(other.box));
  }
  // Surfaces in contact form groups; a group is held when one of its surfaces can be stopped, and
  // a surface resting on a held one is held through it. Gravity moves the surfaces of a group
  // that nothing holds alike, so there it brings no two of them closer: 115 touching parts of an
  // engine falling together took 35 substeps a frame while gravity counted, and no contact needed
  // them.
  std::vector<std::uint32_t>& group = scratch.group;
  group.resize(motion.size());
  for (std::size_t s = 0; s < group.size(); ++s) group[s] = std::uint32_t(s);
  const auto root = [&](std::uint32_t s) { return findRoot(group, s); };
  for (const TrianglePair& pair : touching) {
    const std::uint32_t a = root(std::uint32_t(geometry.triangleSurface[pair.first]));
    const std::uint32_t b = root(std::uint32_t(geometry.triangleSurface[pair.second]));
    if (a != b) joinRoots(group, a, b);
  }
  std::vector<char>& held = scratch.held;
  held.assign(motion.size(), 0);
  for (std::size_t s = 0; s < motion.size(); ++s)
    if (motion[s].mayStop || !motion[s].moving) held[root(std::uint32_t(s))] = 1;
  const auto isHeld = [&](std::uint64_t s) { return held[root(std::uint32_t(s))] != 0; };

  // Surfaces already in contact (`touching`). In a held group: the speed of the fastest corner of
  // a touching triangle pair plus gravity's, the measure kContactReachFraction was calibrated with
  // (their relative speed can be up to twice that). Within one body, and between the surfaces of a
  // group nothing holds, gravity and the common travel move both triangles alike: there, how fast
  // the corners move apart from each other (within one body, from the body's mean velocity).
  ContactAccuracy choice;
  std::vector<std::uint64_t>& touchingSurfaces = scratch.touchingSurfaces;
  touchingSurfaces.clear();
  for (const TrianglePair& pair : touching) {
    const std::uint64_t a = geometry.triangleSurface[pair.first];
    const std::uint64_t b = geometry.triangleSurface[pair.second];
    touchingSurfaces.push_back(std::min(a, b) << 32 | std::max(a, b));
    const auto& first = geometry.triangleVertices[pair.first];
    const auto& second = geometry.triangleVertices[pair.second];
    double closing = 0;
    if (a == b) {
      for (const auto* corners : {&first, &second})
        for (Index v : *corners)
          closing =
              std::max(closing, (vertexVelocity(v).cast<double>() - motion[a].meanVelocity).norm());
    } else if (isHeld(a)) {
      for (const auto* corners : {&first, &second})
        for (Index v : *corners) closing = std::max(closing, double(vertexVelocity(v).norm()));
      closing += gravitySpeed;
    } else {
      for (Index u : first)
        for (Index v : second)
          closing = std::max(closing, double((vertexVelocity(u) - vertexVelocity(v)).norm()));
    }
    choice.closingSpeed = std::max(choice.closingSpeed, closing);
  }
  std::sort(touchingSurfaces.begin(), touchingSurfaces.end());
  const auto inContact = [&](std::uint64_t a, std::uint64_t b) {
    return std::binary_search(touchingSurfaces.begin(), touchingSurfaces.end(),
                              std::min(a, b) << 32 | std::max(a, b));
  };

  // Surfaces not in contact yet: how fast they can close, if they can meet within the frame.
  for (std::size_t a = 0; a < motion.size(); ++a) {
    if (!motion[a].moving) continue;
    // Gravity moves a body's parts alike: only how they move apart from its mean brings a
    // surface onto itself.
    if (geometry.surfaces[a].selfCollision && !inContact(a, a))
      choice.closingSpeed = std::max(choice.closingSpeed, 2 * motion[a].deviation);
    for (std::size_t b = 0; b < motion.size(); ++b) {
      if (b == a || (motion[b].moving && b < a) || inContact(a, b)) continue;  // each pair once
      if (!motion[a].box.intersects(motion[b].box)) continue;
      // Two bodies falling together close at their relative speed, unless one of them lands on
      // the ground (or a static mesh) within the frame and the other closes on it at its whole
      // speed: a 10 kg ball falling 1 m behind a 1 kg one met it at 9.5 m/s in a frame of 4
      // substeps, 0.1 m a substep, and the response's push stored 320 J in the light ball's
      // springs. Gravity adds to the closing speed only where something holds one of them.
      const double fastest = std::max(motion[a].fastest, motion[b].fastest);
      const double closing =
          (motion[a].mayStop || motion[b].mayStop
               ? fastest
               : std::min((motion[a].meanVelocity - motion[b].meanVelocity).norm() +
                              motion[a].deviation + motion[b].deviation,
                          fastest)) +
          (isHeld(a) || isHeld(b) ? gravitySpeed : 0);
      choice.closingSpeed = std::max(choice.closingSpeed, closing);
    }
  }
  const double reach = reachFraction * (skin + edgeLength);
  if (!(reach > 0) || !std::isfinite(choice.closingSpeed)) {
    choice.substeps = kMaxAutoSubsteps;
    return choice;
  }
  const double substeps = std::ceil(choice.closingSpeed * frameTime / reach);
  choice.substeps = int(std::clamp(substeps, double(kMinAutoSubsteps), double(kMaxAutoSubsteps)));
  return choice;
}

double contactEdgeLength(const SceneTopology& topology) {
  // Each edge of each triangle, with a third of the triangle's area.
  std::vector<std::pair<double, double>> edges;
  edges.reserve(topology.triangles.size() * 3);
  double totalArea = 0;
  for (const Triangle& t : topology.triangles) {
    const Vec3 a = topology.restPosition[t[0]], b = topology.restPosition[t[1]],
               c = topology.restPosition[t[2]];
    const double third = 0.5 * double((b - a).cross(c - a).norm()) / 3;
    edges.insert(edges.end(), {{double((b - a).norm()), third},
                               {double((c - b).norm()), third},
                               {double((a - c).norm()), third}});
    totalArea += 3 * third;
  }
  if (edges.empty()) return std::numeric_limits<double>::infinity();
  if (!(totalArea > 0)) {  // every triangle degenerate: count edges alike
    for (auto& edge : edges) edge.second = 1;
    totalArea = double(edges.size());
  }
  // The shortest length whose edges and all shorter ones carry the quantile's share of the area.
  // Each round puts the median of the range in place (nth_element, linear) and keeps the half the
  // quantile lies in, so the whole search is linear in the number of edges and setup stays linear
  // in the scene's size.
  double wanted = kShortEdgeQuantile * totalArea;
  auto lo = edges.begin(), hi = edges.end();
  while (hi - lo > 1) {
    const auto mid = lo + (hi - lo) / 2;
    std::nth_element(lo, mid, hi);
    double below = 0;
    for (auto e = lo; e != mid; ++e) below += e->second;
    if (below >= wanted) {
      hi = mid;
    } else {
      wanted -= below;
      lo = mid;
    }
  }
  return lo->first;
}

}  // namespace softbake
