#include "core/scene/world.hpp"

#include <algorithm>
#include <cmath>

#include "core/collision/geometry.hpp"
#include "core/error.hpp"
#include "core/mesh/mesh_topology.hpp"
#include "core/text.hpp"
#include "core/mesh/weld.hpp"

namespace softbake {

namespace {

// Triangles per volume chunk: big enough to amortise a task, small enough to split 10k faces.
constexpr Index kVolumeChunk = 2048;

void addSprings(World& world, const IndexPair* pairs, std::size_t count, Index offset,
                Scalar stiffness, Scalar dampingRatio) {
  for (std::size_t i = 0; i < count; ++i) {
    const Index a = pairs[i][0] + offset, b = pairs[i][1] + offset;
    const Scalar rest = (world.position[a] - world.position[b]).norm();
    // Critical damping of two masses joined by one spring: 2·sqrt(k·m_a·m_b/(m_a+m_b)).
    const Scalar ma = world.mass[a], mb = world.mass[b];
    const Scalar reduced = ma * mb / (ma + mb);
    world.springs.push_back(
        {a, b, rest, stiffness, dampingRatio * 2 * std::sqrt(stiffness * reduced)});
  }
}

/// Compressed rows of `refCount(item)` references per particle; `visit(item, emit)` calls
/// emit(particle, reference) for each incidence. Two passes: count, then fill.
template <class Visit>
void buildIncidence(std::size_t particleCount, std::size_t itemCount, Visit visit,
                    std::vector<Index>& rowStart, std::vector<Index>& refs) {
  rowStart.assign(particleCount + 1, 0);
  for (std::size_t item = 0; item < itemCount; ++item)
    visit(item, [&](Index particle, Index) { ++rowStart[particle + 1]; });
  for (std::size_t p = 0; p < particleCount; ++p) rowStart[p + 1] += rowStart[p];
  refs.resize(rowStart.back());
  std::vector<Index> cursor(rowStart.begin(), rowStart.end() - 1);
  for (std::size_t item = 0; item < itemCount; ++item)
    visit(item, [&](Index particle, Index ref) { refs[cursor[particle]++] = ref; });
}

void addBody(World& world, const BodySetup& setup, BuildReport* report) {
  auto note = [&](std::string line) {
    if (report) report->notes.push_back(cat("body '", setup.name, "': ", std::move(line)));
  };
  const TriangleMesh& mesh = setup.mesh;
  for (const Triangle& t : mesh.triangles)
    for (Index v : t)
      if (v >= mesh.positions.size())
        throw Error(cat("body '", setup.name, "': triangle index ", v, " is beyond its ",
                        mesh.positions.size(), " vertices"));
  for (const Vec3f& p : mesh.positions)
    if (!p.allFinite())
      throw Error(cat("body '", setup.name, "': a vertex position is not a finite number"));

  WeldedMesh welded = weldByPosition(mesh.positions, mesh.triangles);
  if (welded.triangles.empty())
    throw Error(cat("body '", setup.name, "': the mesh has no usable triangles (",
                    mesh.triangles.size(), " given, ", welded.degenerateTriangles, " degenerate)"));
  if (welded.degenerateTriangles)
    note(cat("dropped ", welded.degenerateTriangles, " degenerate triangles"));
  if (welded.duplicateTriangles)
    note(cat("dropped ", welded.duplicateTriangles, " duplicate triangles"));

  MeshTopology topology = buildTopology(welded.triangles);
  bool closed = topology.closed();
  double volume = closed ? signedVolume(welded.positions, welded.triangles) : 0.0;
  if (closed && volume < 0) {
    // Inside-out (mirrored transform or a file wound clockwise): flip so normals point outwards.
    for (Triangle& t : welded.triangles) std::swap(t[1], t[2]);
    for (Triangle& t : welded.renderTriangles) std::swap(t[1], t[2]);
    volume = -volume;
    note("the mesh was wound inside-out; its triangles were flipped");
  }
  if (closed && !(volume > 0)) closed = false;
  if (!closed && setup.material.pressure != 0) {
    if (topology.boundaryEdges || topology.nonManifoldEdges)
      note(cat("the mesh is open (", topology.boundaryEdges, " boundary, ",
               topology.nonManifoldEdges, " non-manifold edges): pressure is off"));
    else
      note(cat(topology.inconsistentEdges,
               " edges are wound inconsistently, the mesh has no inside: pressure is off"));
  }

  Body body;
  body.name = setup.name;
  body.material = setup.material;
  body.mass = setup.mass;
  body.closed = closed;
  body.selfCollision = setup.selfCollision.value_or(!closed);
  body.restVolume = volume;
  body.gasAmount = closed ? double(setup.material.pressure) * volume : 0.0;
  body.firstParticle = Index(world.position.size());
  body.particleCount = Index(welded.positions.size());
  body.firstTriangle = Index(world.triangles.size());
  body.triangleCount = Index(welded.triangles.size());
  body.render.uvs = mesh.uvs;
  body.render.renderTriangles = std::move(welded.renderTriangles);
  body.render.renderToParticle = std::move(welded.renderToParticle);

  const Index offset = body.firstParticle;
  const Index bodyIndex = Index(world.bodies.size());
  for (const Vec3f& p : welded.positions) {
    world.position.push_back(p.cast<Scalar>());
    world.velocity.push_back(setup.velocity);
    world.particleBody.push_back(bodyIndex);
  }

  // Mass follows vertex area (a third of each adjacent triangle), so a refined patch of the mesh
  // does not weigh more than a coarse one of the same size.
  std::vector<double> area(body.particleCount, 0.0);
  double totalArea = 0;
  for (const Triangle& t : welded.triangles) {
    const Vec3d a = welded.positions[t[0]].cast<double>(),
                b = welded.positions[t[1]].cast<double>(),
                c = welded.positions[t[2]].cast<double>();
    const double triangleArea = 0.5 * (b - a).cross(c - a).norm();
    for (Index v : t) area[v] += triangleArea / 3;
    totalArea += triangleArea;
    world.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  for (Index i = 0; i < body.particleCount; ++i) {
    const Scalar m = Scalar(double(setup.mass) * area[i] / totalArea);
    world.mass.push_back(m);
    world.inverseMass.push_back(1 / m);
  }

  std::size_t pinned = 0;
  auto pin = [&](Index local) {
    if (world.inverseMass[offset + local] != 0) ++pinned;
    world.inverseMass[offset + local] = 0;
  };
  for (Index index : setup.pins.particles) {
    if (index >= body.particleCount)
      throw Error(cat("body '", setup.name, "': pin index ", index, " is beyond its ",
                      body.particleCount, " particles"));
    pin(index);
  }
  for (const PinBox& box : setup.pins.boxes)
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3f p = welded.positions[i];
      if ((p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all()) pin(i);
    }
  if (!setup.pins.boxes.empty() || !setup.pins.particles.empty())
    note(cat(pinned, " particles pinned"));

  body.firstSpring = Index(world.springs.size());
  addSprings(world, topology.edges.data(), topology.edges.size(), offset, setup.material.stiffness,
             setup.material.damping);
  addSprings(world, topology.bendPairs.data(), topology.bendPairs.size(), offset,
             setup.material.bendStiffness, setup.material.damping);
  body.springCount = Index(world.springs.size()) - body.firstSpring;

  for (Index begin = body.firstTriangle; begin < body.firstTriangle + body.triangleCount;
       begin += kVolumeChunk)
    world.volumeChunks.push_back(
        {bodyIndex, begin,
         std::min(begin + kVolumeChunk, body.firstTriangle + body.triangleCount)});
  world.bodies.push_back(std::move(body));
}

}  // namespace

World buildWorld(const SceneSetup& setup, BuildReport* report) {
  World world;
  world.settings = setup.settings;
  world.planes = setup.planes;
  world.staticMeshes = setup.staticMeshes;
  for (PlaneCollider& plane : world.planes) plane.normal.normalize();
  for (const BodySetup& body : setup.bodies) addBody(world, body, report);

  const std::size_t particles = world.position.size();
  world.previousPosition = world.position;
  buildIncidence(
      particles, world.springs.size(),
      [&](std::size_t s, auto emit) {
        emit(world.springs[s].a, Index(2 * s));
        emit(world.springs[s].b, Index(2 * s + 1));
      },
      world.springRowStart, world.springRefs);
  buildIncidence(
      particles, world.triangles.size(),
      [&](std::size_t t, auto emit) {
        for (Index v : world.triangles[t]) emit(v, Index(t));
      },
      world.triangleRowStart, world.triangleRefs);

  world.springForce.assign(world.springs.size(), Vec3::Zero());
  world.triangleForce.assign(world.triangles.size(), Vec3::Zero());
  world.chunkVolume.assign(world.volumeChunks.size(), 0.0);
  world.bodyVolume.assign(world.bodies.size(), 0.0);
  world.bodyPressure.assign(world.bodies.size(), 0);
  for (std::size_t b = 0; b < world.bodies.size(); ++b)
    world.bodyVolume[b] = world.bodies[b].restVolume;
  buildCollisionGeometry(world);
  return world;
}

}  // namespace softbake
