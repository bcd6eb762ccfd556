#include "core/collision/geometry.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/parallel.hpp"
#include "core/scene/incidence.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

namespace {

Box3 inflated(Box3 box, Scalar by) {
  box.min().array() -= by;
  box.max().array() += by;
  return box;
}

/// Appends a static mesh collider as a surface of its own.
void addStaticMesh(CollisionGeometry& geometry, const StaticShape& shape,
                   const StaticMeshCollider& collider) {
  const Index firstVertex = geometry.particleCount + Index(geometry.staticVertex.size());
  const Index surface = Index(geometry.surfaces.size());
  geometry.surfaces.push_back(
      {Index(geometry.triangleVertices.size()), Index(shape.triangles.size()), false, false});
  geometry.restitution.push_back(collider.restitution);
  geometry.friction.push_back(collider.friction);
  geometry.surfaceClosed.push_back(shape.closed);
  geometry.staticVertex.insert(geometry.staticVertex.end(), shape.positions.begin(),
                               shape.positions.end());
  for (const Triangle& t : shape.triangles) {
    geometry.triangleVertices.push_back(
        {t[0] + firstVertex, t[1] + firstVertex, t[2] + firstVertex});
    geometry.triangleSurface.push_back(surface);
  }
}
}  // namespace

CollisionGeometry buildCollisionGeometry(const SceneTopology& topology) {
  CollisionGeometry geometry;
  geometry.particleCount = Index(topology.particleCount());
  geometry.softTriangleCount = Index(topology.triangles.size());
  const CollisionSettings& settings = topology.settings.collisions;

  for (const Body& body : topology.bodies) {
    geometry.surfaces.push_back({body.firstTriangle, body.triangleCount, true, body.selfCollision});
    geometry.restitution.push_back(settings.restitution);
    geometry.friction.push_back(settings.friction);
    geometry.surfaceClosed.push_back(body.closed);
  }
  geometry.triangleVertices = topology.triangles;
  for (std::size_t b = 0; b < topology.bodies.size(); ++b)
    geometry.triangleSurface.insert(geometry.triangleSurface.end(),
                                    topology.bodies[b].triangleCount, Index(b));
  for (std::size_t s = 0; s < topology.staticShapes.size(); ++s)
    addStaticMesh(geometry, topology.staticShapes[s], topology.staticMeshes[s]);
  geometry.selfPatches = buildSelfPatches(geometry, topology.restPosition);
  linkVertexTriangles(geometry);
  return geometry;
}

void linkVertexTriangles(CollisionGeometry& geometry) {
  buildIncidence(
      geometry.particleCount + geometry.staticVertex.size(), geometry.triangleVertices.size(),
      [&](std::size_t t, auto emit) {
        for (Index v : geometry.triangleVertices[t]) emit(v, Index(t));
      },
      geometry.vertexTriangleStart, geometry.vertexTriangles);
}

void dropSurfacePairs(const CollisionGeometry& geometry,
                      std::span<const std::pair<Index, Index>> surfacePairs,
                      std::vector<TrianglePair>& pairs) {
  if (surfacePairs.empty()) return;
  std::erase_if(pairs, [&](const TrianglePair& pair) {
    return std::binary_search(
        surfacePairs.begin(), surfacePairs.end(),
        std::pair(geometry.triangleSurface[pair.first], geometry.triangleSurface[pair.second]));
  });
}

void updateCollisionBoxes(const SceneTopology& topology, const CollisionGeometry& geometry,
                          const SubstepMotion& motion, std::vector<Box3>& boxes) {
  updateCollisionBoxes(topology, geometry, motion, boxes, topology.settings.skin);
}

void updateCollisionBoxes(const SceneTopology& topology, const CollisionGeometry& geometry,
                          const SubstepMotion& motion, std::vector<Box3>& boxes, Scalar margin) {
  std::vector<Box3> particleBoxes;
  updateCollisionBoxes(topology, geometry, motion, boxes, margin, particleBoxes);
}

void updateCollisionBoxes(const SceneTopology& topology, const CollisionGeometry& geometry,
                          const SubstepMotion& motion, std::vector<Box3>& boxes, Scalar margin,
                          std::vector<Box3>& particleBoxes) {
  if (boxes.size() != geometry.triangleVertices.size()) {
    boxes.resize(geometry.triangleVertices.size());
    for (std::size_t t = geometry.softTriangleCount; t < boxes.size(); ++t) {
      Box3 box;
      for (Index v : geometry.triangleVertices[t])
        box.extend(geometry.staticVertex[v - geometry.particleCount]);
      boxes[t] = inflated(box, margin);
    }
  }
  particleBoxes.resize(geometry.particleCount);
  const Vec3* x = motion.end.data();
  const Vec3* x0 = motion.start.data();
  Box3* particleBox = particleBoxes.data();
  const auto pathBox = [=](Index i) {
    Box3 box(x[i]);
    box.extend(x0[i]);
    return inflated(box, margin);
  };
  // The particles' boxes and the triangles' in one parallel loop, each triangle's box made again
  // from its corners' paths rather than read from the particles' boxes: a loop of its own after
  // theirs cost the step a barrier, at every call. The same operations give the same boxes.
  const std::size_t particles = particleBoxes.size();
  const Triangle* triangles = topology.triangles.data();
  Box3* out = boxes.data();
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, particles + geometry.softTriangleCount, kTriangleGrain),
      [=](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          if (k < particles) {
            particleBox[k] = pathBox(Index(k));
            continue;
          }
          const Triangle& corners = triangles[k - particles];
          Box3 box = pathBox(corners[0]);
          box.extend(pathBox(corners[1]));
          box.extend(pathBox(corners[2]));
          out[k - particles] = box;
        }
      });
}

}  // namespace softbake
