#include "output/manifest.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "output/version.hpp"
#include "test_world.hpp"

namespace softbake {
namespace {

using test::listDirectory;
using test::readFile;
using test::ScratchDirectory;

/// A pressurised ball, a ball without pressure and an open quad.
std::shared_ptr<const SceneTopology> makeMixedTopology() {
  SceneSetup setup;
  setup.settings.fps = 30;
  setup.settings.units = "cm";
  BodySetup ball;
  ball.name = "ball";
  ball.mesh = makeIcosphere(1, 1.0f);
  setup.bodies.push_back(ball);
  ball.name = "soft ball";
  ball.material.pressure = 0;
  ball.mesh = makeIcosphere(1, 1.0f, Vec3f(3, 0, 0));
  setup.bodies.push_back(ball);
  BodySetup quad;
  quad.name = "flag";
  quad.mesh.positions = {{0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}};
  quad.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  setup.bodies.push_back(quad);
  return std::make_shared<const SceneTopology>(buildSceneTopology(setup));
}

TEST(Manifest, DescribesSceneBodiesAndSequences) {
  const auto world = makeMixedTopology();
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "mixed");
  Manifest manifest = describeScene(*world, "mixed", 48);
  manifest.sequences.push_back(writer.sequence());
  writeManifest(dir.path(), manifest);

  const nlohmann::json json = nlohmann::json::parse(readFile(dir.path() / "manifest.json"));
  EXPECT_EQ(json["scene"], "mixed");
  EXPECT_EQ(json["softbake_version"], softbakeVersion());
  EXPECT_EQ(json["fps"], 30.0);
  EXPECT_EQ(json["frames"], 48);
  EXPECT_EQ(json["first_frame"], 1);
  EXPECT_EQ(json["frame_padding"], 4);
  EXPECT_EQ(json["units"], "cm");

  ASSERT_EQ(json["bodies"].size(), 3u);
  const nlohmann::json& ball = json["bodies"][0];
  EXPECT_EQ(ball["name"], "ball");
  EXPECT_EQ(ball["particles"], world->bodies[0].particleCount);
  EXPECT_EQ(ball["triangles"], world->bodies[0].triangleCount);
  EXPECT_EQ(ball["closed"], true);
  EXPECT_EQ(ball["pressure"], true);
  EXPECT_EQ(json["bodies"][1]["name"], "soft ball");
  EXPECT_EQ(json["bodies"][1]["closed"], true);
  EXPECT_EQ(json["bodies"][1]["pressure"], false);
  EXPECT_EQ(json["bodies"][2]["particles"], 4);
  EXPECT_EQ(json["bodies"][2]["triangles"], 2);
  EXPECT_EQ(json["bodies"][2]["closed"], false);
  EXPECT_EQ(json["bodies"][2]["pressure"], false);

  ASSERT_EQ(json["sequences"].size(), 1u);
  EXPECT_EQ(json["sequences"][0]["format"], "obj");
  EXPECT_EQ(json["sequences"][0]["pattern"], "obj/mixed_####.obj");
  EXPECT_EQ(json["sequences"][0]["printf_pattern"], "obj/mixed_%04d.obj");
  EXPECT_EQ(json["sequences"][0]["files"], nlohmann::json::array({"obj/mixed.mtl"}));

  EXPECT_EQ(listDirectory(dir.path()), (std::vector<std::string>{"manifest.json", "obj"}));
}

TEST(Manifest, IsByteIdenticalAcrossRunsAndKeepsKeyOrder) {
  ScratchDirectory first, second;
  for (const ScratchDirectory* dir : {&first, &second}) {
    const auto world = makeMixedTopology();
    Manifest manifest = describeScene(*world, "mixed", 10, 5);
    manifest.sequences.push_back(ObjSequenceWriter(world, dir->path(), "mixed", 5).sequence());
    writeManifest(dir->path(), manifest);
  }
  const std::string text = readFile(first.path() / "manifest.json");
  EXPECT_EQ(text, readFile(second.path() / "manifest.json"));
  EXPECT_EQ(text.rfind("{\n  \"scene\": \"mixed\",\n  \"status\": \"complete\",\n  "
                       "\"frames_complete\": 0,\n  \"softbake_version\": ",
                       0),
            0u)
      << text;
  EXPECT_EQ(text.back(), '\n');
  EXPECT_NE(text.find("\"printf_pattern\": \"obj/mixed_%05d.obj\""), std::string::npos) << text;
}

TEST(Manifest, ReadsBackWhatItWrote) {
  ScratchDirectory dir;
  const auto world = makeMixedTopology();
  Manifest manifest = describeScene(*world, "mixed", 10, 5);
  manifest.status = RunStatus::Failed;
  manifest.reason = "writer 'obj': disk full";
  manifest.framesComplete = 7;
  manifest.sequences.push_back(ObjSequenceWriter(world, dir.path(), "mixed", 5).sequence());
  manifest.run = {{"input", "/abs/scene.json"}, {"options", {{"frames", 10}}}};
  writeManifest(dir.path(), manifest);
  const Manifest back = readManifest(dir.path());
  EXPECT_EQ(manifestJson(back), manifestJson(manifest));
  EXPECT_EQ(back.status, RunStatus::Failed);
  EXPECT_EQ(back.framesComplete, 7);
  EXPECT_EQ(sequenceFilePath(back.sequences[0], back.framePadding, 12), "obj/mixed_00012.obj");
  EXPECT_EQ(sequenceFilePath(back.sequences[0], back.framePadding, 123456), "obj/mixed_123456.obj");

  std::ofstream(dir.path() / "manifest.json") << R"({"scene": "x"})";
  try {
    readManifest(dir.path());
    ADD_FAILURE() << "a manifest without its keys was read";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("manifest.json: 'status' is missing"),
              std::string::npos)
        << error.what();
  }
}

TEST(Manifest, UnwritableDirectoryIsAnErrorNamingTheFile) {
  ScratchDirectory dir;
  try {
    writeManifest(dir.path() / "missing", Manifest{});
    FAIL() << "expected softbake::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("manifest.json"), std::string::npos);
  }
}

}  // namespace
}  // namespace softbake
