#include "fuzz/fuzz_entries.hpp"

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/mesh/weld.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/text.hpp"
#include "importers/ply_import.hpp"
#include "importers/scene_file.hpp"

#ifndef SOFTBAKE_EXAMPLES_DIR
#error "SOFTBAKE_EXAMPLES_DIR must name the examples folder"
#endif

namespace softbake::fuzz {

namespace {

// Well below libFuzzer's 2 GiB RSS limit, so a file or scene that asks for more must be refused
// by softbake's own checks (ImportLimits) before it allocates. The face cap keeps one run well
// within the fuzzer's time limit: world building under the sanitizers takes about 40 µs a
// triangle, and a scene of 175 000 took 7.5 s.
constexpr std::uint64_t kImportMemoryMib = 512;
constexpr std::uint64_t kMaxFaces = 100'000;

SceneLoadOptions loadOptions() {
  SceneLoadOptions options;
  options.maxImportMemoryMib = kImportMemoryMib;
  options.maxFaces = kMaxFaces;
  options.maxVertices = 3 * kMaxFaces;
  return options;
}

// `what` runs only when the promise is broken: the checks run per particle and per triangle.
template <class What>
void require(bool holds, What&& what) {
  if (!holds) throw FuzzFinding(what());
}

// An error must say which file it is about: the user has nothing else to go on.
void requireNamed(const Error& error, std::string_view source) {
  const std::string_view message = error.what();
  require(message.starts_with(source), [&] {
    return cat("error does not start with the file's name '", source, "': ", message);
  });
}

bool finite(const Vec3& v) {
  return v.allFinite();
}

}  // namespace

void checkWorld(const SceneTopology& world) {
  const std::size_t particles = world.particleCount();
  require(world.inverseMass.size() == particles && world.restPosition.size() == particles &&
              world.particleBody.size() == particles,
          [&] { return std::string("per-particle arrays differ in length"); });
  for (std::size_t p = 0; p < particles; ++p) {
    require(finite(world.restPosition[p]),
            [&] { return cat("particle ", p, " has a non-finite position"); });
    require(std::isfinite(world.mass[p]) && world.mass[p] > 0,
            [&] { return cat("particle ", p, " has mass ", world.mass[p]); });
    require(std::isfinite(world.inverseMass[p]) && world.inverseMass[p] >= 0,
            [&] { return cat("particle ", p, " has inverse mass ", world.inverseMass[p]); });
  }
  for (const Triangle& t : world.triangles)
    for (Index v : t)
      require(v < particles, [&] { return cat("triangle index ", v, " of ", particles); });
  for (const Spring& s : world.springs) {
    require(s.a < particles && s.b < particles,
            [&] { return std::string("spring index out of range"); });
    require(
        std::isfinite(s.restLength) && std::isfinite(s.stiffness) && std::isfinite(s.damping), [&] {
          return std::string(
              cat("spring ", s.a, "-", s.b, " has a non-finite rest length, stiffness or damping"));
        });
  }
  for (const Body& body : world.bodies) {
    require(std::size_t(body.firstParticle) + body.particleCount <= particles,
            [&] { return cat("body '", body.name, "' reaches past the particles"); });
    require(std::size_t(body.firstTriangle) + body.triangleCount <= world.triangles.size(),
            [&] { return cat("body '", body.name, "' reaches past the triangles"); });
    require(std::isfinite(body.restVolume) && std::isfinite(body.gasAmount),
            [&] { return cat("body '", body.name, "' has a non-finite volume or gas amount"); });
    // A render vertex no triangle uses maps to no particle; the others map to the corners of
    // their body's triangles.
    const RenderMesh& render = body.render;
    for (Index particle : render.renderToParticle)
      require(particle == kNoParticle || particle < body.particleCount, [&] {
        return std::string(
            cat("body '", body.name, "': a render vertex maps to particle ", particle));
      });
    require(render.renderTriangles.size() == body.triangleCount, [&] {
      return cat("body '", body.name, "': ", render.renderTriangles.size(),
                 " render triangles for ", body.triangleCount, " triangles");
    });
    for (Index t = 0; t < body.triangleCount; ++t)
      for (int k = 0; k < 3; ++k) {
        const Index vertex = render.renderTriangles[t][k];
        require(vertex < render.renderToParticle.size() &&
                    body.firstParticle + render.renderToParticle[vertex] ==
                        world.triangles[body.firstTriangle + t][k],
                [&] {
                  return cat("body '", body.name, "': render triangle ", t,
                             " does not match its triangle");
                });
      }
  }
}

namespace {

Outcome buildWorld(const SceneSetup& setup) {
  try {
    checkWorld(buildSceneTopology(setup));
  } catch (const Error&) {
    // World building names the body, not the file: the caller's message says which file.
    return Outcome::kRefused;
  }
  return Outcome::kLoaded;
}

}  // namespace

Outcome sceneText(std::string_view bytes) {
  constexpr std::string_view source = "fuzz.json";
  SceneFile scene;
  try {
    scene = parseSceneText(bytes, source, SOFTBAKE_EXAMPLES_DIR, loadOptions());
  } catch (const Error& error) {
    requireNamed(error, source);
    return Outcome::kRefused;
  }
  return buildWorld(scene.setup);
}

Outcome plyGuard(std::string_view bytes) {
  constexpr std::string_view source = "fuzz.ply";
  try {
    const ImportLimits limits = loadOptions().importLimits();
    const PlyPreparation ply = preparePlyBuffer(bytes, std::string(source), limits);
    if (ply.mesh) {
      for (const Triangle& t : ply.mesh->triangles)
        for (Index v : t)
          require(v < ply.mesh->positions.size(), [&] {
            return cat("strip triangle index ", v, " of ", ply.mesh->positions.size());
          });
      require(ply.mesh->normals.empty() || ply.mesh->normals.size() == ply.mesh->positions.size(),
              [&] { return std::string("normals and positions differ in count"); });
      require(ply.mesh->uvs.empty() || ply.mesh->uvs.size() == ply.mesh->positions.size(),
              [&] { return std::string("UVs and positions differ in count"); });
    }
  } catch (const Error& error) {
    requireNamed(error, source);
    return Outcome::kRefused;
  }
  return Outcome::kLoaded;
}

char meshFormatByte(std::string_view format) {
  for (std::size_t i = 0; i < std::size(kMeshFormats); ++i)
    if (kMeshFormats[i] == format) return char(i);
  throw std::invalid_argument(cat("no mesh format '", format, "'"));
}

Outcome meshImport(std::string_view bytes) {
  if (bytes.empty()) return Outcome::kRefused;
  const auto format = static_cast<unsigned char>(bytes.front()) % std::size(kMeshFormats);
  const std::string name = cat("fuzz", kMeshFormats[format]);
  const SceneLoadOptions options = loadOptions();
  SceneFile scene;
  try {
    scene = sceneFromMeshes(
        importMeshBuffer(bytes.substr(1), name, meshSceneImportOptions(options)), name, options);
  } catch (const Error& error) {
    requireNamed(error, name);
    return Outcome::kRefused;
  }
  return buildWorld(scene.setup);
}

}  // namespace softbake::fuzz
