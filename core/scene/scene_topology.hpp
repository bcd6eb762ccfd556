#pragma once
/// The immutable half of a simulation: every body's particles' rest data, springs, triangles and
/// render maps in flat arrays, the colliders and the settings. Built once by buildSceneTopology()
/// and shared, read-only, by the simulator, the exporters and the renderer (Jolt splits
/// SoftBodySharedSettings from SoftBodyMotionProperties the same way): what changes from step to
/// step is a SimulationState (core/scene/simulation_state.hpp), and each stage's scratch belongs to
/// the stage.
///
/// All bodies share one set of arrays (a body is a range in each), so every stage is one parallel
/// loop over the whole scene and the collision stages can address any particle or triangle by a
/// single global index.

#include <span>
#include <string>
#include <vector>

#include "core/scene/scene_setup.hpp"
#include "core/types.hpp"

namespace softbake {

/// A Hookean spring with damping along its axis. 20 bytes in float: the spring loop streams these.
struct Spring {
  Index a, b;
  Scalar restLength;
  Scalar stiffness;  ///< N/m
  Scalar damping;    ///< N·s/m
};

/// What exporters need to write a body the way its file had it.
struct RenderMesh {
  std::vector<Vec2f> uvs;                 ///< per render vertex; empty when the source had none
  std::vector<Triangle> renderTriangles;  ///< per body triangle, indices into uvs
  std::vector<Index> renderToParticle;    ///< body-local particle of each render vertex
};

struct Body {
  std::string name;
  Index firstParticle = 0, particleCount = 0;
  Index firstTriangle = 0, triangleCount = 0;
  Index firstSpring = 0, springCount = 0;
  Material material;
  Scalar mass = 1;
  Vec3 initialVelocity = Vec3::Zero();  ///< of every particle, m/s
  /// Closed and consistently wound: has a volume, so the gas pressure acts.
  bool closed = false;
  bool selfCollision = false;
  double restVolume = 0;  ///< m³, at the start
  double gasAmount = 0;   ///< nRT = pressure · restVolume, J; zero when pressure is off
  RenderMesh render;
};

/// A static mesh collider as the collision stages see it: welded, so that triangles which touch
/// share vertices (the broad phases skip pairs that share one, and an inside to push out of needs
/// the connectivity), and wound with its normals out where it is closed.
struct StaticShape {
  std::vector<Vec3> positions;
  std::vector<Triangle> triangles;
  bool closed = false;  ///< closed, consistently wound and of non-zero volume
};

/// A run of triangles of one body: the unit of the deterministic volume reduction.
struct TriangleChunk {
  Index body, begin, end;
};

struct SceneTopology {
  SimulationSettings settings;
  std::vector<Body> bodies;
  std::vector<PlaneCollider> planes;
  std::vector<StaticMeshCollider> staticMeshes;

  // Per particle. Mass and inverse mass are read every substep; the rest only at setup.
  std::vector<Scalar> inverseMass;  ///< 0 for pinned particles
  std::vector<Scalar> mass;
  std::vector<Vec3> restPosition;  ///< welded positions at the start: the initial state
  std::vector<Index> particleBody;

  std::vector<Triangle> triangles;  ///< global particle indices, counter-clockwise from outside
  std::vector<Spring> springs;      ///< structural then bending, per body

  // Incidence in compressed rows so each particle sums its own forces in a fixed order: the
  // result is bit-identical for any thread count, with no atomics. A spring reference is
  // 2·spring + (1 if the particle is the spring's `b` end).
  std::vector<Index> springRowStart, springRefs;
  std::vector<Index> triangleRowStart, triangleRefs;
  std::vector<TriangleChunk> volumeChunks;

  std::vector<StaticShape> staticShapes;  ///< per static mesh collider

  std::size_t particleCount() const { return mass.size(); }
  /// Collision surfaces number the bodies first, then the static meshes, and their triangles
  /// likewise: each body's at the same indices as in `triangles`, then each static shape's.
  std::size_t surfaceCount() const { return bodies.size() + staticShapes.size(); }
  /// The first collision triangle of `surface`.
  Index surfaceFirstTriangle(Index surface) const;
  /// The name of collision surface `surface`.
  const std::string& surfaceName(Index surface) const {
    return surface < bodies.size() ? bodies[surface].name
                                   : staticMeshes[surface - bodies.size()].name;
  }
  /// The body's triangles, in global particle indices.
  std::span<const Triangle> bodyTriangles(const Body& body) const {
    return std::span(triangles).subspan(body.firstTriangle, body.triangleCount);
  }
};

/// Smooth normals of `body` at `positions` (every particle, global order), body-local in `out`.
void computeBodyNormals(const SceneTopology& topology, std::span<const Vec3> positions,
                        const Body& body, std::vector<Vec3f>& out);

/// What buildSceneTopology() did that the user should hear about, one line each.
struct BuildReport {
  std::vector<std::string> notes;
};

/// Welds, builds springs, masses and incidence for every body. Throws softbake::Error for a body
/// with no usable triangles or a pin index out of range.
SceneTopology buildSceneTopology(const SceneSetup& setup, BuildReport* report = nullptr);

}  // namespace softbake
