#include "core/collision/detangle.hpp"

#include <algorithm>

#include "core/collision/detection.hpp"
#include "core/collision/response.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

Detangler::Detangler(const SceneTopology& topology, const CollisionGeometry& geometry)
    : movable_(geometry.surfaces.size(), 0), translation_(topology.bodies.size(), Vec3d::Zero()) {
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    bool pinned = false;
    for (Index i = body.firstParticle; i < body.firstParticle + body.particleCount; ++i)
      pinned = pinned || topology.inverseMass[i] == 0;
    movable_[b] = !pinned && body.particleCount > 0;
  }
}

void Detangler::setTangled(const CollisionGeometry& geometry, const InitialOverlaps& overlaps) {
  pairs_.clear();
  moved_.clear();
  for (const SurfaceOverlap& overlap : overlaps.bySurfaces) {
    const Index a = overlap.firstSurface, b = overlap.secondSurface;
    if (a == b || !(movable_[a] || movable_[b])) continue;
    if (!geometry.surfaceClosed[a] && !geometry.surfaceClosed[b]) continue;
    pairs_.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(pairs_.begin(), pairs_.end());
  direction_.assign(pairs_.size(), Vec3d::Zero());
  depth_.assign(pairs_.size(), 0);
  moved_.reserve(pairs_.size());
}

std::size_t Detangler::apply(const SceneTopology& topology, const CollisionGeometry& geometry,
                             const CollisionDetector& detector, SimulationState& state, Scalar dt) {
  if (pairs_.empty()) return 0;
  std::fill(direction_.begin(), direction_.end(), Vec3d::Zero());
  std::fill(depth_.begin(), depth_.end(), Scalar(0));
  // The detector's edge contacts are sorted: the sums are the same for any thread count.
  for (const EdgeContact& edge : detector.edgeContacts()) {
    const Index through = geometry.triangleSurface[edge.edgeTriangle];
    const Index struck = geometry.triangleSurface[edge.triangle];
    const auto pair = std::pair(std::min(through, struck), std::max(through, struck));
    const auto found = std::lower_bound(pairs_.begin(), pairs_.end(), pair);
    if (found == pairs_.end() || *found != pair) continue;
    const EdgeEndsInside inside = findEdgeEndsInside(geometry, state.position, edge);
    if (inside.count == 0) continue;
    const std::size_t k = std::size_t(found - pairs_.begin());
    // The edge's surface goes out of the struck one along the face's outward normal.
    const Vec3d out = inside.normal.cast<double>() * double(inside.count);
    direction_[k] += through == pair.first ? out : Vec3d(-out);
    for (int e = 0; e < inside.count; ++e) depth_[k] = std::max(depth_[k], inside.depth[e]);
  }

  std::fill(translation_.begin(), translation_.end(), Vec3d::Zero());
  moved_.clear();
  const double reach = double(kDetangleSpeed) * double(dt);
  for (std::size_t k = 0; k < pairs_.size(); ++k) {
    const double length = direction_[k].norm();
    if (!(length > 0)) continue;
    const auto [first, second] = pairs_[k];
    moved_.push_back(pairs_[k]);
    const Vec3d move =
        std::min(double(depth_[k] + topology.settings.skin), reach) * (direction_[k] / length);
    const double firstMass = movable_[first] ? double(topology.bodies[first].mass) : 0.0;
    const double secondMass = movable_[second] ? double(topology.bodies[second].mass) : 0.0;
    // Split like the response: each side moves in inverse proportion to its mass; a side that
    // cannot move leaves the whole move to the other.
    const double total = firstMass + secondMass;
    if (movable_[first]) translation_[first] += (secondMass > 0 ? secondMass / total : 1.0) * move;
    if (movable_[second]) translation_[second] -= (firstMass > 0 ? firstMass / total : 1.0) * move;
  }

  std::size_t moved = 0;
  for (std::size_t b = 0; b < translation_.size(); ++b) {
    if (translation_[b] == Vec3d::Zero()) continue;
    ++moved;
    const Vec3 shift = translation_[b].cast<Scalar>();
    const Body& body = topology.bodies[b];
    for (Index i = body.firstParticle; i < body.firstParticle + body.particleCount; ++i)
      state.position[i] += shift;
  }
  return moved;
}

}  // namespace softbake
