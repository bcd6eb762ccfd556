#include "core/collision/geometry.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/mesh/mesh_topology.hpp"
#include "core/mesh/weld.hpp"
#include "core/scene/world.hpp"

namespace softbake {

namespace {
constexpr std::size_t kTriangleGrain = 4096;

Box3 inflated(Box3 box, Scalar by) {
  box.min().array() -= by;
  box.max().array() += by;
  return box;
}
}  // namespace

void buildCollisionGeometry(World& world) {
  CollisionGeometry& geometry = world.collision;
  geometry = {};
  geometry.particleCount = Index(world.particleCount());
  geometry.softTriangleCount = Index(world.triangles.size());
  const CollisionSettings& settings = world.settings.collisions;

  for (const Body& body : world.bodies) {
    geometry.surfaces.push_back({body.firstTriangle, body.triangleCount, true, body.selfCollision});
    geometry.restitution.push_back(settings.restitution);
    geometry.friction.push_back(settings.friction);
    geometry.surfaceClosed.push_back(body.closed);
  }
  geometry.triangleVertices = world.triangles;
  for (std::size_t b = 0; b < world.bodies.size(); ++b)
    geometry.triangleSurface.insert(geometry.triangleSurface.end(), world.bodies[b].triangleCount,
                                    Index(b));

  for (const StaticMeshCollider& collider : world.staticMeshes) {
    // Welded so that neighbouring triangles share vertices: the broad phases skip pairs that
    // share one, and closedness (an inside to push out of) needs the connectivity.
    WeldedMesh welded = weldByPosition(collider.mesh.positions, collider.mesh.triangles);
    bool closed = buildTopology(welded.triangles).closed();
    const double volume = closed ? signedVolume(welded.positions, welded.triangles) : 0.0;
    if (volume < 0)  // wound inside-out: normals must point out for the edge pushes
      for (Triangle& t : welded.triangles) std::swap(t[1], t[2]);
    closed = closed && volume != 0;
    const Index firstVertex = geometry.particleCount + Index(geometry.staticVertex.size());
    const Index surface = Index(geometry.surfaces.size());
    geometry.surfaces.push_back(
        {Index(geometry.triangleVertices.size()), Index(welded.triangles.size()), false, false});
    geometry.restitution.push_back(collider.restitution);
    geometry.friction.push_back(collider.friction);
    geometry.surfaceClosed.push_back(closed);
    for (const Vec3f& p : welded.positions) geometry.staticVertex.push_back(p.cast<Scalar>());
    for (const Triangle& t : welded.triangles) {
      geometry.triangleVertices.push_back(
          {t[0] + firstVertex, t[1] + firstVertex, t[2] + firstVertex});
      geometry.triangleSurface.push_back(surface);
    }
  }

  geometry.triangleBox.resize(geometry.triangleVertices.size());
  const Scalar skin = world.settings.skin;
  for (std::size_t t = geometry.softTriangleCount; t < geometry.triangleVertices.size(); ++t) {
    Box3 box;
    for (Index v : geometry.triangleVertices[t])
      box.extend(geometry.staticVertex[v - geometry.particleCount]);
    geometry.triangleBox[t] = inflated(box, skin);
  }
  updateCollisionBoxes(world);
}

void updateCollisionBoxes(World& world) {
  CollisionGeometry& geometry = world.collision;
  const Triangle* triangles = world.triangles.data();
  const Vec3* x = world.position.data();
  const Vec3* x0 = world.previousPosition.data();
  Box3* boxes = geometry.triangleBox.data();
  const Scalar skin = world.settings.skin;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, geometry.softTriangleCount, kTriangleGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        Box3 box;
                        for (Index v : triangles[t]) {
                          box.extend(x[v]);
                          box.extend(x0[v]);
                        }
                        boxes[t] = inflated(box, skin);
                      }
                    });
}

}  // namespace softbake
