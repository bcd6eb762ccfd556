// Scene files: defaults, every kind of error with its key path, and mesh paths.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/mesh/mesh_topology.hpp"
#include "core/mesh/weld.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/text.hpp"
#include "importers/mesh_import.hpp"
#include "importers/scene_file.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::StartsWith;

constexpr std::string_view kBall = R"({"primitive": "icosphere", "subdivisions": 1})";

SceneFile parse(std::string_view text, const std::filesystem::path& base = {}) {
  return parseScene(nlohmann::json::parse(text), "scene.json", base);
}

std::string sceneError(std::string_view text, const std::filesystem::path& base = {}) {
  try {
    parse(text, base);
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

// A scene of one ball whose body JSON is `body` with the ball's mesh.
std::string oneBody(std::string_view extra) {
  return std::string(R"({"bodies": [{"mesh": )") + std::string(kBall) +
         (extra.empty() ? "" : ", ") + std::string(extra) + "}]}";
}

TEST(SceneFile, FillsDefaults) {
  const SceneFile scene = parse(oneBody(""));
  EXPECT_EQ(scene.setup.name, "scene");  // the stem of "scene.json"
  EXPECT_EQ(scene.setup.settings.fps, 24);
  EXPECT_EQ(scene.setup.settings.frames, 240);
  EXPECT_EQ(scene.setup.settings.substeps, 0);
  EXPECT_EQ(scene.setup.settings.gravity, Vec3(0, Scalar(-9.81), 0));
  EXPECT_EQ(scene.setup.settings.units, "m");
  EXPECT_EQ(scene.setup.settings.maxSpeed, 1000);
  EXPECT_EQ(scene.setup.settings.skin, Scalar(0.001));
  ASSERT_EQ(scene.setup.bodies.size(), 1u);
  const BodySetup& body = scene.setup.bodies[0];
  EXPECT_EQ(body.name, "body0");
  EXPECT_EQ(body.mesh.name, "body0");
  EXPECT_EQ(body.mesh.positions.size(), 42u);  // icosphere level 1
  EXPECT_EQ(body.material.stiffness, findMaterialPreset("rubber")->stiffness);
  EXPECT_EQ(body.mass, 1);
  EXPECT_EQ(body.velocity, Vec3::Zero());
  EXPECT_TRUE(scene.setup.planes.empty());
  EXPECT_EQ(scene.output.framePadding, 4);
  EXPECT_TRUE(scene.output.obj);
  EXPECT_TRUE(scene.notes.empty());
}

TEST(SceneFile, ReadsEveryKey) {
  const SceneFile scene = parse(R"({
    "name": "demo",
    "settings": {"fps": 30, "frames": 12, "substeps": 8, "gravity": [0, -1.62, 0], "units": "cm",
                 "max_speed": 50, "skin": 0},
    "bodies": [{"name": "b", "mesh": {"primitive": "icosphere", "subdivisions": 2, "radius": 2},
                "merge_meshes": true,
                "transform": {"translate": [1, 2, 3], "rotate": [0, 0, 0], "scale": 0.5},
                "material": {"preset": "jelly", "stiffness": 123, "bend_stiffness": 0,
                             "damping": 1, "pressure": 0, "thickness": 0.01},
                "mass": 2.5, "velocity": [1, 0, -1],
                "pins": {"indices": [0, 7], "boxes": [{"min": [-1, -1, -1], "max": [1, 1, 1]}]}}],
    "colliders": [{"type": "plane", "name": "floor", "point": [0, -1, 0], "normal": [0, 2, 0],
                   "restitution": 0.5, "friction": 0.1},
                  {"type": "mesh", "mesh": {"primitive": "icosphere"},
                   "transform": {"scale": [1, 2, 1]}, "restitution": 1, "friction": 0}],
    "output": {"frame_padding": 6, "obj": false}
  })");
  const SimulationSettings& s = scene.setup.settings;
  EXPECT_EQ(scene.setup.name, "demo");
  EXPECT_EQ(s.fps, 30);
  EXPECT_EQ(s.frames, 12);
  EXPECT_EQ(s.substeps, 8);
  EXPECT_EQ(s.gravity, Vec3(0, Scalar(-1.62), 0));
  EXPECT_EQ(s.units, "cm");
  EXPECT_EQ(s.maxSpeed, 50);
  EXPECT_EQ(s.skin, 0);
  const BodySetup& body = scene.setup.bodies.at(0);
  EXPECT_EQ(body.name, "b");
  Eigen::AlignedBox3f bounds;
  for (const Vec3f& p : body.mesh.positions) bounds.extend(p);
  EXPECT_TRUE(bounds.center().isApprox(Vec3f(1, 2, 3), 1e-5f));
  EXPECT_NEAR(bounds.sizes().maxCoeff(), 2, 1e-5);  // radius 2, scaled by a half
  const Material jelly = *findMaterialPreset("jelly");
  EXPECT_EQ(body.material.stiffness, 123);
  EXPECT_EQ(body.material.bendStiffness, 0);
  EXPECT_EQ(body.material.damping, 1);
  EXPECT_EQ(body.material.pressure, 0);
  EXPECT_EQ(body.material.thickness, Scalar(0.01));
  EXPECT_NE(jelly.stiffness, 123);
  EXPECT_EQ(body.mass, Scalar(2.5));
  EXPECT_EQ(body.velocity, Vec3(1, 0, -1));
  // The icosphere's vertices are its particles' render vertices, in its own order.
  EXPECT_EQ(body.pins.vertices, (std::vector<Index>{0, 7}));
  ASSERT_EQ(body.pins.boxes.size(), 1u);
  EXPECT_EQ(body.pins.boxes[0].max, Vec3f(1, 1, 1));

  ASSERT_EQ(scene.setup.planes.size(), 1u);
  const PlaneCollider& plane = scene.setup.planes[0];
  EXPECT_EQ(plane.name, "floor");
  EXPECT_EQ(plane.point, Vec3(0, -1, 0));
  EXPECT_EQ(plane.normal, Vec3(0, 1, 0));  // normalised
  EXPECT_EQ(plane.restitution, Scalar(0.5));
  EXPECT_EQ(plane.friction, Scalar(0.1));
  ASSERT_EQ(scene.setup.staticMeshes.size(), 1u);
  const StaticMeshCollider& collider = scene.setup.staticMeshes[0];
  EXPECT_EQ(collider.name, "collider1");
  EXPECT_EQ(collider.mesh.positions.size(), 642u);
  EXPECT_EQ(collider.restitution, 1);
  EXPECT_EQ(scene.output.framePadding, 6);
  EXPECT_FALSE(scene.output.obj);
}

TEST(SceneFile, ErrorsNameTheKeyPath) {
  struct Case {
    std::string json;
    std::string error;
  };
  const std::string ball(kBall);
  const std::string two = R"({"bodies": [{"mesh": )" + ball + "}, {\"mesh\": " + ball + ", ";
  const std::vector<Case> cases = {
      {two + R"("material": {"stiffness": "hard"}}]})",
       "scene.json: bodies[1].material.stiffness: expected number"},
      {two + R"("material": {"stifness": 5}}]})",
       "scene.json: bodies[1].material: unknown key 'stifness' (did you mean 'stiffness'?)"},
      {two + R"("material": {"stiffness": 0}}]})",
       "scene.json: bodies[1].material.stiffness: expected a number > 0"},
      {two + R"("material": {"damping": 1.5}}]})",
       "scene.json: bodies[1].material.damping: expected a number in [0, 1]"},
      {two + R"("material": {"pressure": -1}}]})",
       "scene.json: bodies[1].material.pressure: expected a number >= 0"},
      {two + R"("material": "rubbr"}]})",
       "scene.json: bodies[1].material: unknown material preset 'rubbr' (valid: stiff, rubber, "
       "jelly, balloon)"},
      {two + R"("material": {"preset": "steel"}}]})",
       "scene.json: bodies[1].material.preset: unknown material preset 'steel' (valid: stiff, "
       "rubber, jelly, balloon)"},
      {two + R"("material": 3}]})",
       "scene.json: bodies[1].material: expected string (a preset) or object"},
      {two + R"("mass": 0}]})", "scene.json: bodies[1].mass: expected a number > 0"},
      {two + R"("velocity": [1, 2]}]})",
       "scene.json: bodies[1].velocity: expected array of 3 numbers"},
      {two + R"("velocity": [1, true, 2]}]})",
       "scene.json: bodies[1].velocity[1]: expected number"},
      {two + R"("merge_meshes": "no"}]})", "scene.json: bodies[1].merge_meshes: expected boolean"},
      {two + R"("name": ""}]})", "scene.json: bodies[1].name: expected a non-empty string"},
      {two + R"("name": "body0"}]})",
       "scene.json: bodies[1]: body name 'body0' is already used by bodies[0]"},
      {two + R"("transform": {"scale": 0}}]})",
       "scene.json: bodies[1].transform.scale: expected a non-zero number"},
      {two + R"("transform": {"scale": [1, 0, 1]}}]})",
       "scene.json: bodies[1].transform.scale[1]: expected a non-zero number"},
      {two + R"("transform": {"scale": "big"}}]})",
       "scene.json: bodies[1].transform.scale: expected number or array of 3 numbers"},
      {two + R"("transform": {"rotation": [0, 0, 0]}}]})",
       "scene.json: bodies[1].transform: unknown key 'rotation' (did you mean 'rotate'?)"},
      {two + R"("pins": {"indices": [-1]}}]})",
       "scene.json: bodies[1].pins.indices[0]: expected an integer in [0, 4294967294]"},
      {two + R"("pins": {"indices": [1.5]}}]})",
       "scene.json: bodies[1].pins.indices[0]: expected integer"},
      {two + R"("pins": {"indices": [0, 42]}}]})",
       "scene.json: bodies[1].pins.indices[1]: vertex 42 is beyond the 42 vertices of the "
       "icosphere "
       "(indices count from 0)"},
      {two + R"("pins": {"particles": [42]}}]})",
       "scene.json: bodies[1].pins.particles[0]: particle 42 is beyond the 42 particles of the "
       "icosphere (indices count from 0)"},
      {two + R"("pins": {"boxes": [{"min": [0, 2, 0], "max": [1, 1, 1]}]}}]})",
       "scene.json: bodies[1].pins.boxes[0]: expected min <= max on every axis"},
      {two + R"("pins": {"boxes": [{"min": [0, 0, 0]}]}}]})",
       "scene.json: bodies[1].pins.boxes[0]: missing key 'max'"},
      {two + R"("shininess": 2}]})",
       "scene.json: bodies[1]: unknown key 'shininess' (valid keys: name, mesh, merge_meshes, "
       "transform, "
       "material, mass, velocity, pins, self_collision, color)"},
      {R"({"bodies": [{"name": "x"}]})", "scene.json: bodies[0]: missing key 'mesh'"},
      {R"({"bodies": [{"mesh": 7}]})",
       "scene.json: bodies[0].mesh: expected string (a mesh file) or object (a primitive)"},
      {R"({"bodies": [{"mesh": {"primitive": "cube"}}]})",
       "scene.json: bodies[0].mesh.primitive: unknown primitive 'cube' (valid: icosphere)"},
      {R"({"bodies": [{"mesh": {"radius": 1}}]})",
       "scene.json: bodies[0].mesh: missing key 'primitive'"},
      {R"({"bodies": [{"mesh": {"primitive": "icosphere", "subdivisions": 9}}]})",
       "scene.json: bodies[0].mesh.subdivisions: expected an integer in [0, 7]"},
      {R"({"bodies": [{"mesh": {"primitive": "icosphere", "radius": -1}}]})",
       "scene.json: bodies[0].mesh.radius: expected a number > 0"},
      {R"({"bodies": [{"mesh": ""}]})", "scene.json: bodies[0].mesh: expected a non-empty string"},
      {R"({"bodies": []})", "scene.json: bodies: expected at least one body"},
      {R"({"bodies": {}})", "scene.json: bodies: expected array"},
      {R"({})", "scene.json: missing key 'bodies'"},
      {R"([])", "scene.json: expected object"},
      {R"({"name": 5, "bodies": []})", "scene.json: name: expected string"},
      {R"({"version": 2})",
       "scene.json: unknown key 'version' (valid keys: name, settings, bodies, colliders, output, "
       "render)"},
      {oneBody("").insert(1, R"("settings": {"fps": 0}, )"),
       "scene.json: settings.fps: expected a number above 0 and at most 1e+06"},
      {oneBody("").insert(1, R"("settings": {"frames": 2.5}, )"),
       "scene.json: settings.frames: expected a whole number from 1 to 10000000"},
      {oneBody("").insert(1, R"("settings": {"frames": 0}, )"),
       "scene.json: settings.frames: expected a whole number from 1 to 10000000"},
      {oneBody("").insert(1, R"("settings": {"substeps": "often"}, )"),
       "scene.json: settings.substeps: expected \"auto\" or a whole number from 1 to 1073741824"},
      {oneBody("").insert(1, R"("settings": {"substeps": 0}, )"),
       "scene.json: settings.substeps: expected \"auto\" or a whole number from 1 to 1073741824"},
      {oneBody("").insert(1, R"("settings": {"gravity": [0, "down", 0]}, )"),
       "scene.json: settings.gravity[1]: expected number"},
      {oneBody("").insert(1, R"("settings": {"units": ""}, )"),
       "scene.json: settings.units: expected a non-empty string"},
      {oneBody("").insert(1, R"("settings": {"max_speed": -5}, )"),
       "scene.json: settings.max_speed: expected a number > 0"},
      {oneBody("").insert(1, R"("settings": {"skin": -0.1}, )"),
       "scene.json: settings.skin: expected a number >= 0"},
      {oneBody("").insert(1, R"("settings": {"fsp": 24}, )"),
       "scene.json: settings: unknown key 'fsp' (did you mean 'fps'?)"},
      {oneBody("").insert(1, R"("settings": [], )"), "scene.json: settings: expected object"},
      {oneBody("").insert(1, R"("colliders": [{"type": "box"}], )"),
       "scene.json: colliders[0].type: unknown collider type 'box' (valid: plane, mesh)"},
      {oneBody("").insert(1, R"("colliders": [{"name": "ground"}], )"),
       "scene.json: colliders[0]: missing key 'type'"},
      {oneBody("").insert(1, R"("colliders": ["plane"], )"),
       "scene.json: colliders[0]: expected object"},
      {oneBody("").insert(
           1, R"("colliders": [{"type": "plane"}, {"type": "plane", "normal": [0, 0, 0]}], )"),
       "scene.json: colliders[1].normal: expected a non-zero vector"},
      {oneBody("").insert(1, R"("colliders": [{"type": "plane", "restitution": 1.5}], )"),
       "scene.json: colliders[0].restitution: expected a number in [0, 1]"},
      {oneBody("").insert(1, R"("colliders": [{"type": "plane", "friction": -1}], )"),
       "scene.json: colliders[0].friction: expected a number >= 0"},
      {oneBody("").insert(1, R"("colliders": [{"type": "plane", "mesh": "a.obj"}], )"),
       "scene.json: colliders[0]: unknown key 'mesh' (valid keys: type, name, point, normal, "
       "restitution, friction)"},
      {oneBody("").insert(1, R"("colliders": [{"type": "mesh"}], )"),
       "scene.json: colliders[0]: missing key 'mesh'"},
      {oneBody("").insert(1, R"("output": {"frame_padding": 10}, )"),
       "scene.json: output.frame_padding: expected a whole number from 1 to 9"},
      {oneBody("").insert(1, R"("output": {"obj": "yes"}, )"),
       "scene.json: output.obj: expected boolean"},
      {oneBody("").insert(1, R"("output": {"ply": true}, )"),
       "scene.json: output: unknown key 'ply' (valid keys: frame_padding, obj, contacts, png, "
       "vdb, pc2, mdd)"},
  };
  for (const Case& c : cases) EXPECT_EQ(sceneError(c.json), c.error) << c.json;
}

TEST(SceneFile, MeshPathsAreRelativeToTheSceneFile) {
  test::ScratchDir dir;
  std::filesystem::create_directories(dir / "scenes" / "meshes");
  std::filesystem::copy_file(test::testMeshes() / "ico4.obj",
                             dir / "scenes" / "meshes" / "ico4.obj");
  std::filesystem::copy_file(test::testMeshes() / "ico4.mtl",
                             dir / "scenes" / "meshes" / "ico4.mtl");
  const auto sceneFile =
      dir.write("scenes/ball.json", R"({
    "bodies": [{"name": "ball", "mesh": "meshes/ico4.obj", "transform": {"translate": [0, 3, 0]}}],
    "colliders": [{"type": "mesh", "name": "rock", "mesh": ")" +
                                        (test::testMeshes() / "fels.3ds").string() + R"("}]
  })");
  const SceneFile scene = loadSceneFile(sceneFile);
  EXPECT_EQ(scene.setup.name, "ball");
  ASSERT_EQ(scene.setup.bodies.size(), 1u);
  const BodySetup& ball = scene.setup.bodies[0];
  EXPECT_EQ(ball.name, "ball");
  EXPECT_EQ(weldByPosition(ball.mesh.positions, ball.mesh.triangles).positions.size(), 642u);
  Eigen::AlignedBox3f bounds, original;
  for (const Vec3f& p : ball.mesh.positions) bounds.extend(p);
  const ImportedMeshes source = importMeshFile(test::testMeshes() / "ico4.obj");
  for (const Vec3f& p : source.meshes.at(0).positions) original.extend(p);
  EXPECT_TRUE(bounds.center().isApprox(original.center() + Vec3f(0, 3, 0), 1e-5f));
  ASSERT_EQ(scene.setup.staticMeshes.size(), 1u);  // an absolute path works as well
  EXPECT_EQ(scene.setup.staticMeshes[0].mesh.triangles.size(), 768u);

  // Missing files name the key path and the path they were looked for at.
  const auto missing =
      dir.write("scenes/missing.json", R"({"bodies": [{"mesh": "meshes/nope.obj"}]})");
  EXPECT_THAT([&] { loadSceneFile(missing); },
              ::testing::ThrowsMessage<Error>(::testing::StrEq(
                  missing.string() + ": bodies[0].mesh: mesh file not found: " +
                  (dir / "scenes" / "meshes" / "nope.obj").lexically_normal().string())));
}

TEST(SceneFile, ImportErrorsComeWithTheKeyPath) {
  const std::filesystem::path broken = test::testMeshes() / "broken";
  EXPECT_EQ(sceneError(R"({"bodies": [{"mesh": "empty.obj"}]})", broken),
            "scene.json: bodies[0].mesh: " + (broken / "empty.obj").lexically_normal().string() +
                ": cannot import (assimp: OBJ-file is too small.)");
}

TEST(SceneFile, SyntaxErrorsNameTheFileLineAndColumn) {
  test::ScratchDir dir;
  const auto file = dir.write("bad.json", "{\n  \"bodies\": [\n    {\"mesh\" \"a.obj\"}\n  ]\n}\n");
  // The column is where the offending token ends: the closing quote of "a.obj".
  EXPECT_THAT([&] { loadSceneFile(file); },
              ::testing::ThrowsMessage<Error>(::testing::StrEq(
                  file.string() + ": line 3, column 19: invalid JSON: syntax error while parsing "
                                  "object separator - unexpected string literal; expected ':'")));
  EXPECT_THAT([&] { loadSceneFile(dir / "absent.json"); },
              ::testing::ThrowsMessage<Error>(
                  ::testing::StrEq((dir / "absent.json").string() + ": file not found")));
}

TEST(SceneFile, NegativeScaleKeepsBodiesWoundOutward) {
  const SceneFile scene = parse(oneBody(R"("transform": {"scale": [-1, 1, 1]})"));
  const TriangleMesh& mesh = scene.setup.bodies.at(0).mesh;
  EXPECT_GT(signedVolume(mesh.positions, mesh.triangles), 0);
}

TEST(SceneFile, MultiMeshFilesGiveOneBodyPerMeshUnlessMerged) {
  const std::string fbx = "cubes_with_mirroring_and_pivot.fbx";
  const SceneFile split = parse(R"({"bodies": [{"name": "cubes", "mesh": ")" + fbx +
                                    R"(", "mass": 2, "material": "jelly"}]})",
                                test::testMeshes());
  std::vector<std::string> names;
  for (const BodySetup& body : split.setup.bodies) {
    names.push_back(body.name);
    EXPECT_EQ(body.mass, 2);
    EXPECT_EQ(body.material.stiffness, findMaterialPreset("jelly")->stiffness);
    EXPECT_GT(signedVolume(body.mesh.positions, body.mesh.triangles), 0) << body.name;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"cubes/Cube2", "cubes/Cube1", "cubes/Cube3",
                                             "cubes/Cube1_2"}));

  const SceneFile merged =
      parse(R"({"bodies": [{"name": "cubes", "mesh": ")" + fbx + R"(", "merge_meshes": true}]})",
            test::testMeshes());
  ASSERT_EQ(merged.setup.bodies.size(), 1u);
  EXPECT_EQ(merged.setup.bodies[0].name, "cubes");
  EXPECT_EQ(merged.setup.bodies[0].mesh.triangles.size(), 420u);

  EXPECT_EQ(sceneError(R"({"bodies": [{"mesh": ")" + fbx + R"(", "pins": {"indices": [0]}}]})",
                       test::testMeshes()),
            "scene.json: bodies[0].pins.indices: vertex indices need a single mesh, but the file "
            "gives 4; set merge_meshes to true or pin with boxes");
}

TEST(SceneFile, ReadsTheCollisionKeys) {
  const SceneFile scene = parse(R"({
    "settings": {"collisions": {"broadphase": "bvh", "levels": 2, "response": "paper",
                                "restitution": 0.5, "friction": 0.1,
                                "initial_overlap": "ignore", "failsafe": false,
                                "contacts_in_step": false, "self_collision": false}},
    "bodies": [{"mesh": {"primitive": "icosphere"}, "self_collision": true},
               {"mesh": {"primitive": "icosphere"}, "transform": {"translate": [0, 3, 0]}}],
    "output": {"contacts": true}
  })");
  const CollisionSettings& collisions = scene.setup.settings.collisions;
  EXPECT_EQ(collisions.broadPhase, BroadPhaseKind::Bvh);
  EXPECT_EQ(collisions.subdivisionLevels, 2);
  EXPECT_EQ(collisions.response, ResponseMode::Paper);
  EXPECT_FLOAT_EQ(collisions.restitution, 0.5f);
  EXPECT_FLOAT_EQ(collisions.friction, 0.1f);
  EXPECT_EQ(collisions.initialOverlap, InitialOverlapMode::Ignore);
  EXPECT_FALSE(collisions.failsafe);
  EXPECT_FALSE(collisions.contactsInStep);
  EXPECT_FALSE(collisions.selfCollision);
  // A body's own key wins; one without it takes the scene's.
  const SceneTopology topology = buildSceneTopology(scene.setup);
  EXPECT_TRUE(topology.bodies[0].selfCollision);
  EXPECT_FALSE(topology.bodies[1].selfCollision);
  const CollisionSettings defaults =
      parse(R"({"bodies": [{"mesh": {"primitive": "icosphere"}}]})").setup.settings.collisions;
  EXPECT_TRUE(defaults.failsafe);
  EXPECT_TRUE(defaults.contactsInStep);
  EXPECT_TRUE(defaults.selfCollision);
  EXPECT_EQ(scene.setup.bodies[0].selfCollision, std::optional<bool>(true));
  EXPECT_TRUE(scene.output.contacts);
  EXPECT_FALSE(parse(R"({"bodies": [{"mesh": {"primitive": "icosphere"}}]})")
                   .setup.bodies[0]
                   .selfCollision.has_value());
}

TEST(SceneFile, CollisionKeyErrorsNameTheKeyPath) {
  const char* body = R"("bodies": [{"mesh": {"primitive": "icosphere"}}])";
  EXPECT_THAT(
      sceneError(cat(R"({"settings": {"collisions": {"broadphase": "octree"}}, )", body, "}")),
      ::testing::HasSubstr("settings.collisions.broadphase: expected \"sbhash\""));
  EXPECT_THAT(sceneError(cat(R"({"settings": {"collisions": {"response": "soft"}}, )", body, "}")),
              ::testing::HasSubstr("settings.collisions.response"));
  EXPECT_THAT(sceneError(cat(R"({"settings": {"collisions": {"levels": 12}}, )", body, "}")),
              ::testing::HasSubstr("settings.collisions.levels"));
  EXPECT_THAT(
      sceneError(cat(R"({"settings": {"collisions": {"initial_overlap": "glue"}}, )", body, "}")),
      ::testing::HasSubstr(
          R"(settings.collisions.initial_overlap: expected "set_aside", "separate" or "ignore")"));
  EXPECT_THAT(sceneError(cat(R"({"settings": {"collisions": {"failsafe": "on"}}, )", body, "}")),
              ::testing::HasSubstr("settings.collisions.failsafe"));
  EXPECT_THAT(
      sceneError(R"({"bodies": [{"mesh": {"primitive": "icosphere"}, "self_collision": 1}]})"),
      ::testing::HasSubstr("bodies[0].self_collision"));
}

TEST(SceneFile, ReadsTheRenderKeysAndBodyColours) {
  const SceneFile scene = parse(R"({
    "bodies": [{"mesh": {"primitive": "icosphere"}, "color": [0.9, 0.2, 0.1]},
               {"mesh": {"primitive": "icosphere"}}],
    "render": {"size": [640, 360], "samples": 8, "wireframe": true, "contact_spheres": false,
               "contact_color": [1, 0, 0], "contact_radius": 0.02, "contacts_view": "opaque",
               "camera": {"position": [0, 2, 6], "target": [0, 1, 0], "fov": 35}}
  })");
  const RenderSettings& render = scene.render;
  EXPECT_EQ(render.width, std::optional<int>(640));
  EXPECT_EQ(render.height, std::optional<int>(360));
  EXPECT_EQ(render.samples, std::optional<int>(8));
  EXPECT_EQ(render.wireframe, std::optional<bool>(true));
  EXPECT_EQ(render.contactSpheres, std::optional<bool>(false));
  EXPECT_EQ(render.contactsView, std::optional<std::string>("opaque"));
  EXPECT_FALSE(render.contactColorsByKind);
  const SceneFile xray = parse(R"({"bodies": [{"mesh": {"primitive": "icosphere"}}],
    "render": {"contacts_view": "xray", "contact_color": "kind"}})");
  EXPECT_EQ(xray.render.contactsView, std::optional<std::string>("xray"));
  EXPECT_TRUE(xray.render.contactColorsByKind);
  EXPECT_FALSE(xray.render.contactColor);
  ASSERT_TRUE(render.cameraPosition && render.cameraTarget);
  EXPECT_TRUE(render.cameraPosition->isApprox(Vec3f(0, 2, 6)));
  EXPECT_FLOAT_EQ(*render.fovDegrees, 35);
  ASSERT_EQ(render.bodyColors.size(), 2u);
  EXPECT_TRUE(render.bodyColors[0] && render.bodyColors[0]->isApprox(Vec3f(0.9f, 0.2f, 0.1f)));
  EXPECT_FALSE(render.bodyColors[1]);
}

TEST(SceneFile, RenderKeyErrorsNameTheKeyPath) {
  const std::string body = R"("bodies": [{"mesh": {"primitive": "icosphere"}}])";
  EXPECT_THAT(sceneError(R"({"render": {"size": [640]}, )" + body + "}"),
              ::testing::HasSubstr("render.size: expected [width, height]"));
  EXPECT_THAT(sceneError(R"({"render": {"camera": {"position": [0, 1, 2]}}, )" + body + "}"),
              ::testing::HasSubstr("render.camera: expected both"));
  EXPECT_THAT(
      sceneError(R"({"render": {"camera": {"position": [0, 1, 2], "target": [0, 1, 2]}}, )" + body +
                 "}"),
      ::testing::HasSubstr("render.camera.target: the camera's target is its position"));
  EXPECT_THAT(sceneError(R"({"render": {"contacts_view": "glass"}, )" + body + "}"),
              ::testing::HasSubstr(R"(render.contacts_view: expected "xray" or "opaque")"));
  EXPECT_THAT(sceneError(R"({"render": {"contacts_view": true}, )" + body + "}"),
              ::testing::HasSubstr("render.contacts_view: expected"));
  EXPECT_THAT(sceneError(R"({"render": {"contact_color": "red"}, )" + body + "}"),
              ::testing::HasSubstr("render.contact_color: expected three numbers"));
  EXPECT_THAT(
      sceneError(R"({"bodies": [{"mesh": {"primitive": "icosphere"}, "color": [2, 0, 0]}]})"),
      ::testing::HasSubstr("bodies[0].color"));
}

}  // namespace
}  // namespace softbake
