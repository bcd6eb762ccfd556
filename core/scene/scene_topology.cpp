#include "core/scene/scene_topology.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/mesh/mesh_topology.hpp"
#include "core/mesh/normals.hpp"
#include "core/mesh/weld.hpp"
#include "core/scene/incidence.hpp"
#include "core/scene/simulation_state.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

StaticShape staticShape(const StaticMeshCollider& collider) {
  WeldedMesh welded = weldByPosition(collider.mesh.positions, collider.mesh.triangles);
  bool closed = buildTopology(welded.triangles).closed();
  const double volume = closed ? signedVolume(welded.positions, welded.triangles) : 0.0;
  if (volume < 0)  // wound inside-out: normals must point out for the edge pushes
    for (Triangle& t : welded.triangles) std::swap(t[1], t[2]);
  StaticShape shape;
  shape.closed = closed && volume != 0;
  for (const Vec3f& p : welded.positions) shape.positions.push_back(p.cast<Scalar>());
  shape.triangles = std::move(welded.triangles);
  return shape;
}

// Triangles per volume chunk: big enough to amortise a task, small enough to split 10k faces.
constexpr Index kVolumeChunk = 2048;

/// Adds one line to the report, prefixed with the body's name.
class BodyNotes {
 public:
  BodyNotes(const std::string& body, BuildReport* report) : body_(body), report_(report) {}
  void operator()(std::string line) const {
    if (report_) report_->notes.push_back(cat("body '", body_, "': ", std::move(line)));
  }

 private:
  const std::string& body_;
  BuildReport* report_;
};

void addSprings(SceneTopology& scene, const IndexPair* pairs, std::size_t count, Index offset,
                Scalar stiffness, Scalar dampingRatio) {
  for (std::size_t i = 0; i < count; ++i) {
    const Index a = pairs[i][0] + offset, b = pairs[i][1] + offset;
    const Scalar rest = (scene.restPosition[a] - scene.restPosition[b]).norm();
    // Critical damping of two masses joined by one spring: 2·sqrt(k·m_a·m_b/(m_a+m_b)).
    const Scalar ma = scene.mass[a], mb = scene.mass[b];
    const Scalar reduced = ma * mb / (ma + mb);
    scene.springs.push_back(
        {a, b, rest, stiffness, dampingRatio * 2 * std::sqrt(stiffness * reduced)});
  }
}

/// Throws for an index past the vertices or a position that is not a finite number.
void checkMesh(const BodySetup& setup) {
  const TriangleMesh& mesh = setup.mesh;
  for (const Triangle& t : mesh.triangles)
    for (Index v : t)
      if (v >= mesh.positions.size())
        throw Error(cat("body '", setup.name, "': triangle index ", v, " is beyond its ",
                        mesh.positions.size(), " vertices"));
  for (const Vec3f& p : mesh.positions)
    if (!p.allFinite())
      throw Error(cat("body '", setup.name, "': a vertex position is not a finite number"));
}

/// A closed surface whose volume is at most this fraction of its area to the power 3/2 is flat.
/// A sphere has 0.094, a sheet 1 mm thick and a metre wide 3.5e-4; 1e-6 is a slab 3 µm thick a
/// metre wide, less than float positions can resolve on a body of that size.
constexpr double kFlatVolumeRatio = 1e-6;

/// A welded triangle's area, in double: the mass spread and the flatness test both sum it.
double triangleArea(const WeldedMesh& welded, const Triangle& t) {
  const Vec3d a = welded.positions[t[0]].cast<double>(), b = welded.positions[t[1]].cast<double>(),
              c = welded.positions[t[2]].cast<double>();
  return 0.5 * (b - a).cross(c - a).norm();
}

double surfaceArea(const WeldedMesh& welded) {
  double area = 0;
  for (const Triangle& t : welded.triangles) area += triangleArea(welded, t);
  return area;
}

/// A body's mesh welded and wound outwards, with its edges. A body without an inside gets no
/// volume and so no pressure.
struct WeldedBody {
  WeldedMesh welded;
  MeshTopology topology;
  bool closed = false;
  double volume = 0;
};

WeldedBody weldBody(const BodySetup& setup, const BodyNotes& note) {
  const TriangleMesh& mesh = setup.mesh;
  WeldedBody result{weldByPosition(mesh.positions, mesh.triangles), {}, false, 0};
  WeldedMesh& welded = result.welded;
  if (welded.triangles.empty())
    throw Error(cat("body '", setup.name, "': the mesh has no usable triangles (",
                    mesh.triangles.size(), " given, ", welded.degenerateTriangles, " degenerate)"));
  if (welded.degenerateTriangles)
    note(cat("dropped ", welded.degenerateTriangles, " degenerate triangles"));
  if (welded.duplicateTriangles)
    note(cat("dropped ", welded.duplicateTriangles, " duplicate triangles"));

  result.topology = buildTopology(welded.triangles);
  const MeshTopology& topology = result.topology;
  bool& closed = result.closed;
  double& volume = result.volume;
  closed = topology.closed();
  volume = closed ? signedVolume(welded.positions, welded.triangles) : 0.0;
  if (closed && volume < 0) {
    // Inside-out (mirrored transform or a file wound clockwise): flip so normals point outwards.
    for (Triangle& t : welded.triangles) std::swap(t[1], t[2]);
    for (Triangle& t : welded.renderTriangles) std::swap(t[1], t[2]);
    volume = -volume;
    note("the mesh was wound inside-out; its triangles were flipped");
  }
  const double area = closed ? surfaceArea(welded) : 0.0;
  if (closed && !(volume > kFlatVolumeRatio * std::pow(area, 1.5))) {
    // A closed surface folded flat (a box of zero thickness, as CAD exports trim and edge pieces)
    // encloses only rounding: V_rest is noise, and the gas law's nRT/V and the bulk term's
    // K/V_rest turn that noise into forces without bound. It has no inside to keep.
    closed = false;
    if (setup.material.pressure != 0 || setup.material.bulkModulus != 0)
      note(cat("the mesh is closed but flat (volume ", volume, " inside an area of ", area,
               "): it is taken as open, pressure is off"));
  } else if (!closed && setup.material.pressure != 0) {
    if (topology.boundaryEdges || topology.nonManifoldEdges)
      note(cat("the mesh is open (", topology.boundaryEdges, " boundary, ",
               topology.nonManifoldEdges, " non-manifold edges): pressure is off"));
    else
      note(cat(topology.inconsistentEdges,
               " edges are wound inconsistently, the mesh has no inside: pressure is off"));
  }
  return result;
}

/// Appends the body's particles and triangles. Mass follows vertex area (a third of each
/// adjacent triangle), so a refined patch of the mesh does not weigh more than a coarse one of
/// the same size.
void addParticles(SceneTopology& scene, const WeldedMesh& welded, Index bodyIndex, Scalar mass) {
  const Index offset = Index(scene.restPosition.size());
  for (const Vec3f& p : welded.positions) {
    scene.restPosition.push_back(p.cast<Scalar>());
    scene.particleBody.push_back(bodyIndex);
  }
  std::vector<double> area(welded.positions.size(), 0.0);
  double totalArea = 0;
  for (const Triangle& t : welded.triangles) {
    const double triangle = triangleArea(welded, t);
    for (Index v : t) area[v] += triangle / 3;
    totalArea += triangle;
    scene.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  for (double particleArea : area) {
    const Scalar m = Scalar(double(mass) * particleArea / totalArea);
    scene.mass.push_back(m);
    scene.inverseMass.push_back(1 / m);
  }
}

/// Zeroes the inverse mass of the pinned particles of `body`.
void pinParticles(SceneTopology& scene, const BodySetup& setup, const Body& body,
                  const std::vector<Vec3f>& positions, const BodyNotes& note) {
  std::size_t pinned = 0;
  auto pin = [&](Index local) {
    Scalar& inverseMass = scene.inverseMass[body.firstParticle + local];
    if (inverseMass != 0) ++pinned;
    inverseMass = 0;
  };
  const std::vector<Index>& renderToParticle = body.render.renderToParticle;
  for (Index vertex : setup.pins.vertices) {
    if (vertex >= renderToParticle.size())
      throw Error(cat("body '", setup.name, "': pinned vertex ", vertex, " is beyond its ",
                      renderToParticle.size(), " vertices"));
    if (renderToParticle[vertex] == kNoParticle)
      throw Error(cat("body '", setup.name, "': pinned vertex ", vertex,
                      " is on no triangle the simulation keeps (unused, or only on degenerate "
                      "triangles)"));
    pin(renderToParticle[vertex]);
  }
  for (Index index : setup.pins.particles) {
    if (index >= body.particleCount)
      throw Error(cat("body '", setup.name, "': pin index ", index, " is beyond its ",
                      body.particleCount, " particles"));
    pin(index);
  }
  for (const PinBox& box : setup.pins.boxes)
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3f p = positions[i];
      if ((p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all()) pin(i);
    }
  if (!setup.pins.boxes.empty() || !setup.pins.particles.empty() || !setup.pins.vertices.empty())
    note(cat(pinned, " particles pinned"));
}

void addBody(SceneTopology& scene, const BodySetup& setup, BuildReport* report) {
  const BodyNotes note(setup.name, report);
  checkMesh(setup);
  WeldedBody weldedBody = weldBody(setup, note);
  WeldedMesh& welded = weldedBody.welded;
  const MeshTopology& topology = weldedBody.topology;
  const bool closed = weldedBody.closed;
  const double volume = weldedBody.volume;

  Body body;
  body.name = setup.name;
  body.material = setup.material;
  body.mass = setup.mass;
  body.initialVelocity = setup.velocity;
  body.closed = closed;
  body.selfCollision = setup.selfCollision.value_or(scene.settings.collisions.selfCollision);
  body.restVolume = volume;
  body.gasAmount = closed ? double(setup.material.pressure) * volume : 0.0;
  body.firstParticle = Index(scene.restPosition.size());
  body.particleCount = Index(welded.positions.size());
  body.firstTriangle = Index(scene.triangles.size());
  body.triangleCount = Index(welded.triangles.size());
  body.render.uvs = setup.mesh.uvs;
  body.render.renderTriangles = std::move(welded.renderTriangles);
  body.render.renderToParticle = std::move(welded.renderToParticle);

  const Index bodyIndex = Index(scene.bodies.size());
  addParticles(scene, welded, bodyIndex, setup.mass);
  pinParticles(scene, setup, body, welded.positions, note);

  body.firstSpring = Index(scene.springs.size());
  addSprings(scene, topology.edges.data(), topology.edges.size(), body.firstParticle,
             setup.material.stiffness, setup.material.damping);
  addSprings(scene, topology.bendPairs.data(), topology.bendPairs.size(), body.firstParticle,
             setup.material.bendStiffness, setup.material.damping);
  body.springCount = Index(scene.springs.size()) - body.firstSpring;

  for (Index begin = body.firstTriangle; begin < body.firstTriangle + body.triangleCount;
       begin += kVolumeChunk)
    scene.volumeChunks.push_back(
        {bodyIndex, begin,
         std::min(begin + kVolumeChunk, body.firstTriangle + body.triangleCount)});
  scene.bodies.push_back(std::move(body));
}

}  // namespace

SceneTopology buildSceneTopology(const SceneSetup& setup, BuildReport* report) {
  SceneTopology scene;
  scene.settings = setup.settings;
  scene.planes = setup.planes;
  scene.staticMeshes = setup.staticMeshes;
  for (PlaneCollider& plane : scene.planes) plane.normal.normalize();
  for (const BodySetup& body : setup.bodies) addBody(scene, body, report);

  const std::size_t particles = scene.particleCount();
  buildIncidence(
      particles, scene.springs.size(),
      [&](std::size_t s, auto emit) {
        emit(scene.springs[s].a, Index(2 * s));
        emit(scene.springs[s].b, Index(2 * s + 1));
      },
      scene.springRowStart, scene.springRefs);
  buildIncidence(
      particles, scene.triangles.size(),
      [&](std::size_t t, auto emit) {
        for (Index v : scene.triangles[t]) emit(v, Index(t));
      },
      scene.triangleRowStart, scene.triangleRefs);
  for (const StaticMeshCollider& collider : scene.staticMeshes)
    scene.staticShapes.push_back(staticShape(collider));
  return scene;
}

Index SceneTopology::surfaceFirstTriangle(Index surface) const {
  if (surface < bodies.size()) return bodies[surface].firstTriangle;
  Index first = Index(triangles.size());
  for (Index s = 0; s < surface - bodies.size(); ++s)
    first += Index(staticShapes[s].triangles.size());
  return first;
}

void computeBodyNormals(const SceneTopology& topology, std::span<const Vec3> positions,
                        const Body& body, std::vector<Vec3f>& out) {
  computeSmoothNormals(topology.bodyTriangles(body), positions, body.firstParticle,
                       body.particleCount, out);
}

SimulationState initialState(const SceneTopology& topology) {
  SimulationState state;
  state.position = topology.restPosition;
  state.velocity.resize(topology.particleCount());
  for (const Body& body : topology.bodies)
    std::fill_n(state.velocity.begin() + body.firstParticle, body.particleCount,
                body.initialVelocity);
  return state;
}

}  // namespace softbake
