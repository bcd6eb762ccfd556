#pragma once
/// The simulation's state: every body's particles, springs and triangles in flat arrays.
///
/// All bodies share one set of arrays (a body is a range in each), so every stage is one parallel
/// loop over the whole scene and the collision stages can address any particle or triangle by a
/// single global index. Setup data (topology, rest lengths, masses) is built once by buildWorld();
/// the stepper only rewrites positions, velocities and the scratch arrays, never reallocates.

#include <string>
#include <vector>

#include "core/collision/geometry.hpp"
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
  /// Closed and consistently wound: has a volume, so the gas pressure acts.
  bool closed = false;
  bool selfCollision = false;
  double restVolume = 0;  ///< m³, at the start
  double gasAmount = 0;   ///< nRT = pressure · restVolume, J; zero when pressure is off
  RenderMesh render;
};

/// A run of triangles of one body: the unit of the deterministic volume reduction.
struct TriangleChunk {
  Index body, begin, end;
};

struct World {
  std::vector<Body> bodies;
  std::vector<PlaneCollider> planes;
  std::vector<StaticMeshCollider> staticMeshes;
  SimulationSettings settings;

  // Particle state, hot: touched every substep.
  std::vector<Vec3> position;
  std::vector<Vec3> previousPosition;  ///< start of the current substep: collision segments
  std::vector<Vec3> velocity;
  std::vector<Scalar> inverseMass;  ///< 0 for pinned particles
  // Particle data, cold.
  std::vector<Scalar> mass;
  std::vector<Index> particleBody;

  std::vector<Triangle> triangles;  ///< global particle indices, counter-clockwise from outside
  std::vector<Spring> springs;      ///< structural then bending, per body

  // Incidence in compressed rows so each particle sums its own forces in a fixed order: the
  // result is bit-identical for any thread count, with no atomics. A spring reference is
  // 2·spring + (1 if the particle is the spring's `b` end).
  std::vector<Index> springRowStart, springRefs;
  std::vector<Index> triangleRowStart, triangleRefs;

  // Scratch, sized once by buildWorld().
  std::vector<Vec3> springForce;    ///< force on each spring's `a` end
  std::vector<Vec3> triangleForce;  ///< pressure force on each corner of each triangle
  std::vector<TriangleChunk> volumeChunks;
  std::vector<double> chunkVolume;
  std::vector<double> bodyVolume;    ///< current enclosed volume per body
  std::vector<Scalar> bodyPressure;  ///< current gas pressure per body, Pa

  CollisionGeometry collision;  ///< soft and static triangles for the collision pipeline

  std::size_t particleCount() const { return position.size(); }
};

/// What buildWorld() did that the user should hear about, one line each.
struct BuildReport {
  std::vector<std::string> notes;
};

/// Welds, builds springs, masses and incidence for every body. Throws softbake::Error for a body
/// with no usable triangles or a pin index out of range.
World buildWorld(const SceneSetup& setup, BuildReport* report = nullptr);

}  // namespace softbake
