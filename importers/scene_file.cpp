#include "importers/scene_file.hpp"

#include "core/collision/initial_overlap.hpp"

#include <cmath>
#include <limits>
#include <map>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/mesh/weld.hpp"
#include "core/text.hpp"
#include "importers/json_reader.hpp"
#include "importers/mesh_import.hpp"
#include "importers/mesh_transform.hpp"
#include "importers/option_table.hpp"

namespace softbake {

namespace {

constexpr int kMaxSubdivisions = 7;             // 163842 vertices; one more level is 655362
constexpr long long kMaxMebibytes = 1LL << 40;  // a byte count that still fits 64 bits

std::string validPresetNames() {
  std::string names;
  for (const NamedMaterial& preset : materialPresets())
    names += cat(names.empty() ? "" : ", ", preset.name);
  return names;
}

Vec3 toVec3(const Eigen::Vector3d& v) {
  return v.cast<Scalar>();
}

std::string nonEmptyString(const JsonValue& value) {
  std::string text = value.string();
  if (text.empty()) value.fail("expected a non-empty string");
  return text;
}

// The scene name becomes every output file's stem and the OBJ `mtllib` argument.
std::string sceneName(const JsonValue& value) {
  std::string text = nonEmptyString(value);
  if (text != fileSafeSceneName(text))
    value.fail(cat("'", text, "' cannot name output files: use no '/', '\\' or whitespace"));
  return text;
}

// Checks the keys of the object at `value` that options of the table override, as the options
// check them; the parser then reads them as they are.
void checkOptionKeys(const JsonValue& value) {
  for (const OptionSpec& spec : optionTable()) {
    const std::size_t dot = spec.sceneKey.rfind('.');
    if (dot == std::string_view::npos || spec.sceneKey.substr(0, dot) != value.path()) continue;
    const std::string key(spec.sceneKey.substr(dot + 1));
    if (!value.raw().is_object() || !value.raw().contains(key)) continue;
    // A flag standing for one value of a key (--no-response: response "none") leaves the key's
    // check to the option that takes any of its values.
    if (spec.kind == OptionKind::Flag && !spec.value.is_boolean()) continue;
    const JsonValue child = value.child(key);
    if (auto error = checkOptionValue(spec, child.raw(), '"')) child.fail(error->message);
  }
}

class SceneParser {
 public:
  SceneParser(std::string_view source, const std::filesystem::path& baseDirectory,
              const SceneLoadOptions& options)
      : source_(source), baseDirectory_(baseDirectory), options_(options) {}

  /// Writes `json`'s settings, output and render keys over `scene`.
  SceneFile apply(const nlohmann::json& json, SceneFile scene) {
    scene_ = std::move(scene);
    const JsonObject root = JsonValue(json, source_, "").object({"settings", "output", "render"});
    if (auto settings = root.find("settings")) parseSettings(*settings);
    if (auto output = root.find("output")) parseOutput(*output);
    if (auto render = root.find("render")) parseRender(*render);
    return std::move(scene_);
  }

  SceneFile parse(const nlohmann::json& json) {
    const JsonObject root =
        JsonValue(json, source_, "")
            .object({"name", "settings", "bodies", "colliders", "output", "render"});
    scene_.setup.name = fileSafeSceneName(std::filesystem::path(source_).stem().string());
    if (auto name = root.find("name")) scene_.setup.name = sceneName(*name);
    if (auto settings = root.find("settings")) parseSettings(*settings);

    const JsonValue bodies = root.at("bodies");
    const std::vector<JsonValue> bodyValues = bodies.array();
    if (bodyValues.empty()) bodies.fail("expected at least one body");
    // Before any mesh is read.
    if (bodyValues.size() > options_.maxBodies)
      bodies.fail(cat(bodyValues.size(), " bodies, above the limit of ", options_.maxBodies,
                      " (--max-bodies raises it)"));
    std::map<std::string, std::string> bodyNames;  // name -> key path that gave it
    for (std::size_t i = 0; i < bodyValues.size(); ++i) {
      parseBody(bodyValues[i], i, bodyNames);
      if (scene_.setup.bodies.size() > options_.maxBodies)
        bodyValues[i].fail(cat("its file's meshes bring the scene to ", scene_.setup.bodies.size(),
                               " bodies, above the limit of ", options_.maxBodies,
                               " (--max-bodies raises it)"));
    }

    if (auto colliders = root.find("colliders")) {
      const std::vector<JsonValue> colliderValues = colliders->array();
      for (std::size_t i = 0; i < colliderValues.size(); ++i) parseCollider(colliderValues[i], i);
    }
    if (auto output = root.find("output")) parseOutput(*output);
    if (auto render = root.find("render")) parseRender(*render);
    scene_.render.bodyColors.resize(scene_.setup.bodies.size());
    return std::move(scene_);
  }

 private:
  void parseSettings(const JsonValue& value) {
    const JsonObject object = value.object({"fps", "frames", "integrator", "substeps", "gravity",
                                            "units", "max_speed", "skin", "collisions", "import"});
    checkOptionKeys(value);
    SimulationSettings& settings = scene_.setup.settings;
    if (auto fps = object.find("fps")) settings.fps = fps->raw().get<double>();
    if (auto frames = object.find("frames")) settings.frames = frames->raw().get<int>();
    if (auto integrator = object.find("integrator"))
      parseIntegrator(integrator->string(), settings.integrator);
    if (auto substeps = object.find("substeps"))
      settings.substeps = substeps->raw().is_string() ? 0 : substeps->raw().get<int>();
    if (auto gravity = object.find("gravity")) settings.gravity = toVec3(gravity->vector3());
    if (auto units = object.find("units")) settings.units = nonEmptyString(*units);
    if (auto maxSpeed = object.find("max_speed"))
      settings.maxSpeed = Scalar(maxSpeed->numberAbove(0));
    if (auto skin = object.find("skin")) settings.skin = Scalar(skin->numberAtLeast(0));
    if (auto collisions = object.find("collisions")) parseCollisions(*collisions);
    if (auto import = object.find("import")) parseImport(*import);
  }

  // Before the bodies, whose meshes it applies to. The command line's values win.
  void parseImport(const JsonValue& value) {
    const JsonObject object = value.object(
        {"accept_lossy", "max_vertices", "max_faces", "max_memory_mib", "max_seconds"});
    if (auto accept = object.find("accept_lossy"))
      options_.acceptLossyImport = options_.acceptLossyImport || accept->boolean();
    if (auto vertices = object.find("max_vertices"))
      limits_.maxVertices = std::uint64_t(vertices->integerAtLeast(1));
    if (auto faces = object.find("max_faces"))
      limits_.maxFaces = std::uint64_t(faces->integerAtLeast(1));
    if (auto memory = object.find("max_memory_mib"))
      limits_.maxMemoryBytes = std::uint64_t(memory->integerIn(1, kMaxMebibytes)) << 20;
    if (auto seconds = object.find("max_seconds"))
      limits_.maxSeconds = std::uint64_t(seconds->integerIn(1, kMaxImportSeconds));
  }

  MeshImportOptions importOptions(bool merge) const {
    return {.mergeMeshes = merge,
            .acceptLossy = options_.acceptLossyImport,
            .limits = options_.importLimits(limits_)};
  }

  void parseCollisions(const JsonValue& value) {
    const JsonObject object =
        value.object({"broadphase", "levels", "response", "restitution", "friction", "pair_cache",
                      "initial_overlap", "failsafe", "contacts_in_step", "self_collision"});
    checkOptionKeys(value);
    CollisionSettings& collisions = scene_.setup.settings.collisions;
    if (auto broadPhase = object.find("broadphase"))
      parseBroadPhase(broadPhase->string(), collisions.broadPhase);
    if (auto levels = object.find("levels"))
      collisions.subdivisionLevels = levels->raw().get<int>();
    if (auto response = object.find("response"))
      parseResponseMode(response->string(), collisions.response);
    if (auto restitution = object.find("restitution"))
      collisions.restitution = Scalar(restitution->numberIn(0, 1));
    if (auto friction = object.find("friction"))
      collisions.friction = Scalar(friction->numberAtLeast(0));
    if (auto pairCache = object.find("pair_cache"))
      collisions.pairCache = pairCache->raw().get<bool>();
    if (auto failsafe = object.find("failsafe")) collisions.failsafe = failsafe->boolean();
    if (auto inStep = object.find("contacts_in_step"))
      collisions.contactsInStep = inStep->boolean();
    if (auto self = object.find("self_collision")) collisions.selfCollision = self->boolean();
    if (auto initialOverlap = object.find("initial_overlap")) {
      if (!parseInitialOverlapMode(initialOverlap->string(), collisions.initialOverlap))
        initialOverlap->fail(cat("expected ", alternatives(initialOverlapModeNames(), "\"")));
    }
  }

  // The meshes a `mesh` key names, in their own space. A file may hold several. With `numbering`,
  // also where the file's vertices went (FileVertices).
  std::vector<TriangleMesh> readMeshes(const JsonValue& value, bool merge,
                                       FileVertices* numbering = nullptr) {
    if (value.isString()) {
      const std::filesystem::path given = value.string();
      if (given.empty()) value.fail("expected a non-empty string");
      const std::filesystem::path resolved =
          (given.is_absolute() ? given : baseDirectory_ / given).lexically_normal();
      std::error_code error;
      if (!std::filesystem::exists(resolved, error))
        value.fail(cat("mesh file not found: ", resolved.string()));
      ImportedMeshes imported;
      scene_.inputFiles.push_back(resolved);
      try {
        MeshImportOptions options = importOptions(merge);
        options.numberFileVertices = numbering != nullptr;
        imported = importMeshFile(resolved, options);
      } catch (const Error& importError) {
        value.fail(importError.what());
      }
      std::uint64_t vertices = 0, faces = 0;
      for (const TriangleMesh& mesh : imported.meshes) {
        vertices += mesh.positions.size();
        faces += mesh.triangles.size();
      }
      addToScene(value, vertices, faces);
      for (std::string& note : imported.notes) scene_.notes.push_back(std::move(note));
      for (std::string& warning : imported.warnings)
        scene_.warnings.push_back(cat(source_, ": ", value.path(), ": ", warning));
      if (numbering) *numbering = std::move(imported.fileVertices);
      return std::move(imported.meshes);
    }
    if (value.isObject()) {
      const JsonObject object = value.object({"primitive", "subdivisions", "radius"});
      const JsonValue primitive = object.at("primitive");
      if (primitive.string() != "icosphere")
        primitive.fail(cat("unknown primitive '", primitive.string(), "' (valid: icosphere)"));
      int subdivisions = 3;
      float radius = 0.5f;
      if (auto s = object.find("subdivisions"))
        subdivisions = int(s->integerIn(0, kMaxSubdivisions));
      if (auto r = object.find("radius")) radius = float(r->numberAbove(0));
      // Before it is made: 4^subdivisions times an icosahedron's 20 faces and 30 edges.
      const std::uint64_t grow = std::uint64_t(1) << (2 * subdivisions);
      addToScene(value, 10 * grow + 2, 20 * grow);
      TriangleMesh mesh = makeIcosphere(subdivisions, radius);
      mesh.name = "icosphere";
      if (numbering)
        for (Index v = 0; v < mesh.positions.size(); ++v) numbering->places.push_back({0, v});
      return {std::move(mesh)};
    }
    value.fail("expected string (a mesh file) or object (a primitive)");
  }

  // The scene's meshes together stay within the caps of one mesh file. A few lines of JSON can ask
  // for thousands of finely subdivided spheres (found by fuzzing), which would take all of the
  // machine's memory before anything after loading could refuse them.
  void addToScene(const JsonValue& value, std::uint64_t vertices, std::uint64_t faces) {
    const ImportLimits limits = options_.importLimits(limits_);
    sceneVertices_ += vertices;
    sceneFaces_ += faces;
    if (sceneFaces_ > limits.maxFaces)
      value.fail(cat("the scene's meshes come to ", sceneFaces_, " triangles, above the limit of ",
                     limits.maxFaces, " (--max-faces or settings.import.max_faces raises it)"));
    if (sceneVertices_ > limits.maxVertices)
      value.fail(cat("the scene's meshes come to ", sceneVertices_,
                     " vertices, above the limit of ", limits.maxVertices,
                     " (--max-vertices or settings.import.max_vertices raises it)"));
  }

  static Eigen::Affine3d parseTransform(const JsonValue& value) {
    const JsonObject object = value.object({"translate", "rotate", "scale"});
    Eigen::Vector3d translate = Eigen::Vector3d::Zero(), rotate = Eigen::Vector3d::Zero();
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();
    if (auto t = object.find("translate")) translate = t->vector3();
    if (auto r = object.find("rotate")) rotate = r->vector3();
    if (auto s = object.find("scale")) {
      auto nonZero = [](const JsonValue& component) {
        const double x = component.number();
        // A zero scale flattens the body to nothing: no volume, no simulation.
        if (x == 0) component.fail("expected a non-zero number");
        return x;
      };
      if (s->raw().is_number()) {
        scale.setConstant(nonZero(*s));
      } else if (s->raw().is_array() && s->raw().size() == 3) {
        for (int axis = 0; axis < 3; ++axis) scale[axis] = nonZero(s->element(std::size_t(axis)));
      } else {
        s->fail("expected number or array of 3 numbers");
      }
    }
    return composeTransform(translate, rotate, scale);
  }

  static Material parseMaterial(const JsonValue& value) {
    auto preset = [](const JsonValue& name) {
      const std::optional<Material> material = findMaterialPreset(name.string());
      if (!material)
        name.fail(
            cat("unknown material preset '", name.string(), "' (valid: ", validPresetNames(), ")"));
      return *material;
    };
    if (value.isString()) return preset(value);
    if (!value.isObject()) value.fail("expected string (a preset) or object");
    const JsonObject object = value.object({"preset", "stiffness", "bend_stiffness", "damping",
                                            "pressure", "thickness", "bulk_modulus"});
    Material material = *findMaterialPreset("rubber");
    if (auto name = object.find("preset")) material = preset(*name);
    if (auto k = object.find("stiffness")) material.stiffness = Scalar(k->numberAbove(0));
    if (auto k = object.find("bend_stiffness"))
      material.bendStiffness = Scalar(k->numberAtLeast(0));
    if (auto d = object.find("damping")) material.damping = Scalar(d->numberIn(0, 1));
    if (auto p = object.find("pressure")) material.pressure = Scalar(p->numberAtLeast(0));
    if (auto t = object.find("thickness")) material.thickness = Scalar(t->numberAtLeast(0));
    if (auto k = object.find("bulk_modulus")) material.bulkModulus = Scalar(k->numberAtLeast(0));
    return material;
  }

  // `indices` are the file's vertex numbers here; pinFileVertices() maps them once it is read.
  static Pins parsePins(const JsonValue& value) {
    const JsonObject object = value.object({"indices", "particles", "boxes"});
    Pins pins;
    auto readIndices = [](const JsonValue& indices, std::vector<Index>& out) {
      for (const JsonValue& index : indices.array())
        out.push_back(Index(index.integerIn(0, std::numeric_limits<Index>::max() - 1)));
    };
    if (auto indices = object.find("indices")) readIndices(*indices, pins.vertices);
    if (auto particles = object.find("particles")) readIndices(*particles, pins.particles);
    if (auto boxes = object.find("boxes")) {
      for (const JsonValue& box : boxes->array()) {
        const JsonObject corners = box.object({"min", "max"});
        PinBox pinBox{corners.at("min").vector3().cast<float>(),
                      corners.at("max").vector3().cast<float>()};
        if ((pinBox.min.array() > pinBox.max.array()).any())
          box.fail("expected min <= max on every axis");
        pins.boxes.push_back(pinBox);
      }
    }
    return pins;
  }

  void parseBody(const JsonValue& value, std::size_t index,
                 std::map<std::string, std::string>& names) {
    const JsonObject object = value.object({"name", "mesh", "merge_meshes", "transform", "material",
                                            "mass", "velocity", "pins", "self_collision", "color"});
    BodySetup body;
    body.name = cat("body", index);
    if (auto name = object.find("name")) body.name = nonEmptyString(*name);
    if (auto material = object.find("material")) {
      body.material = parseMaterial(*material);
    } else {
      body.material = *findMaterialPreset("rubber");
    }
    if (auto mass = object.find("mass")) body.mass = Scalar(mass->numberAbove(0));
    if (auto velocity = object.find("velocity")) body.velocity = toVec3(velocity->vector3());
    if (auto self = object.find("self_collision")) body.selfCollision = self->boolean();
    std::optional<Vec3f> color;
    if (auto c = object.find("color")) color = colour(*c);
    Eigen::Affine3d transform = Eigen::Affine3d::Identity();
    if (auto t = object.find("transform")) transform = parseTransform(*t);
    bool merge = false;
    if (auto m = object.find("merge_meshes")) merge = m->boolean();
    std::optional<JsonValue> pinsValue = object.find("pins");
    if (pinsValue) body.pins = parsePins(*pinsValue);

    const JsonValue meshValue = object.at("mesh");
    FileVertices numbering;
    std::vector<TriangleMesh> meshes =
        readMeshes(meshValue, merge, body.pins.vertices.empty() ? nullptr : &numbering);
    // Indices belong to one mesh; across split bodies they would be ambiguous.
    if (meshes.size() > 1 && (!body.pins.vertices.empty() || !body.pins.particles.empty())) {
      const bool vertices = !body.pins.vertices.empty();
      pinsValue->child(vertices ? "indices" : "particles")
          .fail(cat(vertices ? "vertex" : "particle",
                    " indices need a single mesh, but the file gives ", meshes.size(),
                    "; set merge_meshes to true or pin with boxes"));
    }
    if (!body.pins.vertices.empty())
      pinFileVertices(pinsValue->child("indices"), meshValue, numbering, body.pins.vertices);
    for (TriangleMesh& mesh : meshes) {
      BodySetup split = body;
      if (meshes.size() > 1) split.name = cat(body.name, '/', mesh.name);
      auto [existing, inserted] = names.try_emplace(split.name, value.path());
      if (!inserted)
        value.fail(cat("body name '", split.name, "' is already used by ", existing->second));
      transformMesh(mesh, transform);
      // Welded where core will weld it: a non-uniform scale changes which vertices are one.
      if (!body.pins.particles.empty())
        checkParticlePins(pinsValue->child("particles"), meshValue, mesh, body.pins.particles);
      mesh.name = split.name;
      split.mesh = std::move(mesh);
      scene_.setup.bodies.push_back(std::move(split));
      scene_.render.bodyColors.resize(scene_.setup.bodies.size());
      scene_.render.bodyColors.back() = color;
    }
  }

  // How messages name the mesh a `mesh` key gives: its file as the scene names it.
  static std::string meshLabel(const JsonValue& mesh) {
    return mesh.isString() ? mesh.string() : std::string("the icosphere");
  }

  // `vertices` hold the file's vertex numbers (`pins.indices`, at `indices`); they become the
  // imported mesh's vertices at the same places.
  static void pinFileVertices(const JsonValue& indices, const JsonValue& mesh,
                              const FileVertices& numbering, std::vector<Index>& vertices) {
    if (!numbering.unknown.empty())
      indices.fail(
          cat(meshLabel(mesh), ": ", numbering.unknown, "; pin with pins.particles or pins.boxes"));
    const std::vector<JsonValue> values = indices.array();
    for (std::size_t k = 0; k < vertices.size(); ++k) {
      const Index vertex = vertices[k];
      if (vertex >= numbering.places.size())
        values[k].fail(cat("vertex ", vertex, " is beyond the ", numbering.places.size(),
                           " vertices of ", meshLabel(mesh), " (indices count from 0)"));
      const FileVertexPlace& place = numbering.places[vertex];
      if (place.mesh == FileVertexPlace::kNone)
        values[k].fail(cat("vertex ", vertex, " of ", meshLabel(mesh),
                           " is on no triangle, so it is no particle"));
      vertices[k] = place.vertex;
    }
  }

  // Particle indices count the welded particles, which the weld here numbers as core's will.
  static void checkParticlePins(const JsonValue& indices, const JsonValue& mesh,
                                const TriangleMesh& triangles,
                                const std::vector<Index>& particles) {
    const std::size_t count =
        weldByPosition(triangles.positions, triangles.triangles).positions.size();
    const std::vector<JsonValue> values = indices.array();
    for (std::size_t k = 0; k < particles.size(); ++k)
      if (particles[k] >= count)
        values[k].fail(cat("particle ", particles[k], " is beyond the ", count, " particles of ",
                           meshLabel(mesh), " (indices count from 0)"));
  }

  void parseCollider(const JsonValue& value, std::size_t index) {
    if (!value.isObject()) value.fail("expected object");
    const JsonValue typeValue = JsonObject(value).at("type");
    const std::string type = typeValue.string();
    const std::string defaultName = cat("collider", index);
    if (type == "plane") {
      const JsonObject object =
          value.object({"type", "name", "point", "normal", "restitution", "friction"});
      PlaneCollider plane;
      plane.name = defaultName;
      if (auto name = object.find("name")) plane.name = nonEmptyString(*name);
      if (auto point = object.find("point")) plane.point = toVec3(point->vector3());
      if (auto normal = object.find("normal")) {
        const Eigen::Vector3d n = normal->vector3();
        if (!(n.norm() > 0)) normal->fail("expected a non-zero vector");
        plane.normal = toVec3(n.normalized());
      }
      readContact(object, plane.restitution, plane.friction);
      scene_.setup.planes.push_back(std::move(plane));
    } else if (type == "mesh") {
      const JsonObject object =
          value.object({"type", "name", "mesh", "transform", "restitution", "friction"});
      StaticMeshCollider collider;
      collider.name = defaultName;
      if (auto name = object.find("name")) collider.name = nonEmptyString(*name);
      Eigen::Affine3d transform = Eigen::Affine3d::Identity();
      if (auto t = object.find("transform")) transform = parseTransform(*t);
      readContact(object, collider.restitution, collider.friction);
      // A static collider is one surface however many meshes its file holds.
      std::vector<TriangleMesh> meshes = readMeshes(object.at("mesh"), /*merge=*/true);
      collider.mesh = std::move(meshes.front());
      transformMesh(collider.mesh, transform);
      collider.mesh.name = collider.name;
      scene_.setup.staticMeshes.push_back(std::move(collider));
    } else {
      typeValue.fail(cat("unknown collider type '", type, "' (valid: plane, mesh)"));
    }
  }

  static void readContact(const JsonObject& object, Scalar& restitution, Scalar& friction) {
    if (auto r = object.find("restitution")) restitution = Scalar(r->numberIn(0, 1));
    if (auto f = object.find("friction")) friction = Scalar(f->numberAtLeast(0));
  }

  static Vec3f colour(const JsonValue& value) {
    const Eigen::Vector3d rgb = value.vector3();
    if ((rgb.array() < 0).any() || (rgb.array() > 1).any())
      value.fail("expected three numbers in [0, 1] (linear RGB)");
    return rgb.cast<float>();
  }

  void parseRender(const JsonValue& value) {
    const JsonObject object =
        value.object({"size", "samples", "camera", "contact_spheres", "contact_color",
                      "contact_radius", "contacts_view", "wireframe"});
    checkOptionKeys(value);
    RenderSettings& render = scene_.render;
    if (auto size = object.find("size")) {
      render.width = size->raw()[0].get<int>();
      render.height = size->raw()[1].get<int>();
    }
    if (auto samples = object.find("samples")) render.samples = int(samples->integerIn(1, 16));
    if (auto camera = object.find("camera")) {
      const JsonObject c = camera->object({"position", "target", "fov"});
      if (auto position = c.find("position"))
        render.cameraPosition = position->vector3().cast<float>();
      if (auto target = c.find("target")) render.cameraTarget = target->vector3().cast<float>();
      if (auto fov = c.find("fov")) render.fovDegrees = float(fov->numberIn(1, 170));
      if (render.cameraPosition.has_value() != render.cameraTarget.has_value())
        camera->fail("expected both 'position' and 'target', or neither (automatic framing)");
      // Checked here, with its key path, not when the first frame renders (after other outputs
      // have been written, or never with --no-render).
      if (render.cameraPosition && *render.cameraPosition == *render.cameraTarget)
        c.at("target").fail("the camera's target is its position: it would look nowhere");
    }
    if (auto spheres = object.find("contact_spheres"))
      render.contactSpheres = spheres->raw().get<bool>();
    if (auto color = object.find("contact_color")) {
      if (color->isString() && color->string() == "kind")
        render.contactColorsByKind = true;
      else if (color->isString())
        color->fail("expected three numbers in [0, 1] (linear RGB) or \"kind\"");
      else
        render.contactColor = colour(*color);
    }
    if (auto radius = object.find("contact_radius"))
      render.contactRadius = float(radius->numberAbove(0));
    if (auto view = object.find("contacts_view")) render.contactsView = view->string();
    if (auto wireframe = object.find("wireframe")) render.wireframe = wireframe->boolean();
  }

  void parseOutput(const JsonValue& value) {
    const JsonObject object =
        value.object({"frame_padding", "obj", "contacts", "png", "vdb", "pc2", "mdd"});
    checkOptionKeys(value);
    if (auto padding = object.find("frame_padding"))
      scene_.output.framePadding = padding->raw().get<int>();
    if (auto obj = object.find("obj")) scene_.output.obj = obj->boolean();
    if (auto contacts = object.find("contacts"))
      scene_.output.contacts = contacts->raw().get<bool>();
    if (auto png = object.find("png")) scene_.output.png = png->raw().get<bool>();
    if (auto vdb = object.find("vdb")) scene_.output.vdb = vdb->raw().get<bool>();
    if (auto pc2 = object.find("pc2")) scene_.output.pc2 = pc2->raw().get<bool>();
    if (auto mdd = object.find("mdd")) scene_.output.mdd = mdd->raw().get<bool>();
  }

  std::string_view source_;
  std::filesystem::path baseDirectory_;
  SceneLoadOptions options_;
  ImportLimits limits_;                               // the defaults, then the scene's
  std::uint64_t sceneVertices_ = 0, sceneFaces_ = 0;  // of every mesh read so far
  SceneFile scene_;
};

}  // namespace

ImportLimits SceneLoadOptions::importLimits(ImportLimits scene) const {
  if (maxVertices) scene.maxVertices = *maxVertices;
  if (maxFaces) scene.maxFaces = *maxFaces;
  if (maxImportMemoryMib) scene.maxMemoryBytes = *maxImportMemoryMib << 20;
  if (maxImportSeconds) scene.maxSeconds = *maxImportSeconds;
  return scene;
}

SceneFile parseScene(const nlohmann::json& json, std::string_view source,
                     const std::filesystem::path& baseDirectory, const SceneLoadOptions& options) {
  return SceneParser(source, baseDirectory, options).parse(json);
}

void applySceneKeys(SceneFile& scene, const nlohmann::json& document, std::string_view source) {
  scene = SceneParser(source, {}, {}).apply(document, std::move(scene));
}

SceneFile parseSceneText(std::string_view text, std::string_view source,
                         const std::filesystem::path& baseDirectory,
                         const SceneLoadOptions& options) {
  return parseScene(parseJsonText(text, source), source, baseDirectory, options);
}

SceneFile loadSceneFile(const std::filesystem::path& path, const SceneLoadOptions& options) {
  const nlohmann::json json = readJsonFile(path);
  SceneFile scene = parseScene(json, path.string(), path.parent_path(), options);
  scene.inputFiles.insert(scene.inputFiles.begin(), path);
  return scene;
}

std::string fileSafeSceneName(std::string name) {
  for (char& c : name)
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) <= ' ') c = '_';
  return name.empty() ? std::string("scene") : name;
}

}  // namespace softbake
