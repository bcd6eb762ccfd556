// The `softbake` command end to end, run in a child process like a user or a pipeline would run
// it: what it prints, how it exits, and what it leaves on disk.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "softbake_process.hpp"

namespace fs = std::filesystem;

namespace {

using softbake::test::CliTest;
using softbake::test::quoted;
using softbake::test::readFile;
using softbake::test::Result;
using softbake::test::runSoftbake;

/// The meshes in the repository (tests/data/meshes): a missing one fails its test.
fs::path meshes() {
  return SOFTBAKE_TEST_MESHES_DIR;
}
fs::path examples() {
  return fs::path(SOFTBAKE_SOURCE_DIR) / "examples";
}

}  // namespace

TEST_F(CliTest, DefaultSceneWritesFramesAndManifestAndSaysWhere) {
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run --frames 3 -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  for (const char* name : {"obj/default_0001.obj", "obj/default_0002.obj", "obj/default_0003.obj",
                           "obj/default.mtl", "manifest.json"})
    EXPECT_TRUE(fs::exists(out / name)) << name;
  EXPECT_FALSE(fs::exists(out / "obj/default_0004.obj"));
  EXPECT_NE(run.output.find((out / "obj/default_####.obj").string()), std::string::npos)
      << run.output;
  const nlohmann::json manifest = nlohmann::json::parse(readFile(out / "manifest.json"));
  EXPECT_EQ(manifest.at("frames").get<int>(), 3);
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(out))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(CliTest, ALongerRunThenAShorterOneLeavesOneConsistentSequence) {
  const fs::path out = folder_ / "out";
  ASSERT_EQ(runSoftbake("run --frames 5 -q -o " + quoted(out.string())).exitCode, 0);
  ASSERT_EQ(runSoftbake("run --frames 2 -q -o " + quoted(out.string())).exitCode, 0);
  EXPECT_TRUE(fs::exists(out / "obj/default_0002.obj"));
  EXPECT_FALSE(fs::exists(out / "obj/default_0003.obj"));
}

TEST_F(CliTest, OutputIsByteIdenticalForOneAndTwoThreads) {
  const fs::path one = folder_ / "one", two = folder_ / "two";
  ASSERT_EQ(runSoftbake("run --frames 12 -q -j 1 -o " + quoted(one.string())).exitCode, 0);
  ASSERT_EQ(runSoftbake("run --frames 12 -q -j 2 -o " + quoted(two.string())).exitCode, 0);
  for (const char* frame : {"obj/default_0002.obj", "obj/default_0012.obj"}) {
    const std::string a = readFile(one / frame), b = readFile(two / frame);
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << frame << " differs between 1 and 2 threads";
  }
}

TEST_F(CliTest, AMeshFileRunsAsASoftBodyNamedAfterTheFile) {
  const fs::path source = folder_ / "my ball.off";  // a space: the scene name must be made safe
  fs::copy_file(meshes() / "ballA.off", source);
  const fs::path out = folder_ / "out";
  const Result run =
      runSoftbake("run " + quoted(source.string()) + " --frames 2 -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_TRUE(fs::exists(out / "obj/my_ball_0002.obj")) << run.output;
}

TEST_F(CliTest, MissingInputIsAnErrorNamingTheFile) {
  const Result run =
      runSoftbake("run /nonexistent/scene.json -o " + quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 1);
  EXPECT_NE(run.output.find("/nonexistent/scene.json"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("error"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(folder_ / "o")) << "nothing is written for bad input";
}

TEST_F(CliTest, WrongTypeInASceneNamesTheKeyPath) {
  const fs::path scene = writeScene("bad.json", R"({
    "bodies": [{"mesh": {"primitive": "icosphere"}, "material": {"stiffness": "hard"}}]
  })");
  const Result run =
      runSoftbake("run " + quoted(scene.string()) + " -o " + quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 1);
  EXPECT_NE(run.output.find("bodies[0].material.stiffness"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("bad.json"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(folder_ / "o"));
}

TEST_F(CliTest, ASceneNameThatCannotNameFilesIsRefused) {
  const fs::path scene = writeScene("named.json", R"({
    "name": "my scene", "bodies": [{"mesh": {"primitive": "icosphere"}}]
  })");
  const Result run =
      runSoftbake("run " + quoted(scene.string()) + " -o " + quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 1);
  EXPECT_NE(run.output.find("name"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(folder_ / "o"));
}

TEST_F(CliTest, EmptyMeshFileIsAnErrorNotACrash) {
  const Result run = runSoftbake("run " + quoted((meshes() / "broken/empty.obj").string()) +
                                 " -o " + quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("empty.obj"), std::string::npos) << run.output;
}

TEST_F(CliTest, PlyThatCrashesAssimpIsRefusedWithAMessage) {
  const fs::path crash = meshes() / "broken/crash-30d6d0f7c529b3b66b4131700b7a4580cd7082df.ply";
  ASSERT_TRUE(fs::exists(crash));
  const Result run =
      runSoftbake("run " + quoted(crash.string()) + " -o " + quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("crash-30d6d0f7"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(folder_ / "o"));
}

TEST_F(CliTest, BadOptionValuesAreRefused) {
  // Bad input, flags included (docs/commands.md): 1, not CLI11's own 105-109.
  for (const char* arguments : {"run --substeps zero", "run --frames 0", "frobnicate"}) {
    const Result run = runSoftbake(arguments);
    EXPECT_EQ(run.exitCode, 1) << arguments << "\n" << run.output;
  }
}

TEST_F(CliTest, TooFewExplicitSubstepsWarnsWithTheBound) {
  const Result run = runSoftbake("run --integrator explicit --frames 1 --substeps 1 -q -o " +
                                 quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("stability bound"), std::string::npos) << run.output;
}

TEST_F(CliTest, TooFewSubstepsBlowsUpWithAClearErrorAndNoNaNInAnyFile) {
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run --integrator explicit --frames 48 --substeps 1 -q -o " +
                                 quoted(out.string()));
  ASSERT_EQ(run.exitCode, 2) << run.output;  // the simulation failed
  EXPECT_NE(run.output.find("substeps"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("frame"), std::string::npos) << run.output;
  // The manifest says the run failed and why. The frames before the blow-up are written; none is
  // complete, since PNG frames are rendered once the whole shot is simulated.
  const nlohmann::json manifest = nlohmann::json::parse(readFile(out / "manifest.json"));
  EXPECT_EQ(manifest["status"], "failed");
  EXPECT_NE(manifest["reason"].get<std::string>().find("blew up at frame"), std::string::npos);
  EXPECT_EQ(manifest["frames_complete"], 0);
  EXPECT_TRUE(fs::exists(out / "obj/default_0001.obj"));
  EXPECT_FALSE(fs::exists(out / "png/default_0001.png"));
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(out)) {
    // Text files only: the cache's binary floats may hold the bytes "nan" by chance.
    if (!entry.is_regular_file() || entry.path().extension() == ".sbframe") continue;
    const std::string text = readFile(entry.path());
    EXPECT_EQ(text.find("nan"), std::string::npos) << entry.path();
    EXPECT_EQ(text.find("inf"), std::string::npos) << entry.path();
  }
}

TEST_F(CliTest, EveryExampleSceneLoadsAndRunsAFewFrames) {
  int count = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(examples())) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    const fs::path out = folder_ / entry.path().stem();
    const Result run = runSoftbake("run " + quoted(entry.path().string()) + " --frames 3 -q -o " +
                                   quoted(out.string()));
    EXPECT_EQ(run.exitCode, 0) << entry.path() << "\n" << run.output;
    EXPECT_TRUE(fs::exists(out / "manifest.json")) << entry.path();
  }
  EXPECT_GE(count, 4);
}

/// Every example scene, by file name.
std::vector<std::string> exampleNames() {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(examples()))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

class ExampleBake : public CliTest, public ::testing::WithParamInterface<std::string> {};

/// The whole bake through the command, to the example's last frame with its own settings (its own
/// integrator): a blow-up anywhere fails it. Each integrator runs every example to its end in
/// ExampleContacts (tests/contacts), which checks every frame for intersections too.
TEST_P(ExampleBake, RunsToItsLastFrame) {
  const std::string& example = GetParam();
  const fs::path scene = examples() / (example + ".json");
  const fs::path out = folder_ / "out";
  const Result run =
      runSoftbake("run " + quoted(scene.string()) + " --no-render -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const nlohmann::json sceneJson = nlohmann::json::parse(readFile(scene));
  const int frames = sceneJson["settings"].value("frames", 0);
  ASSERT_GT(frames, 0);
  char last[32];
  std::snprintf(last, sizeof last, "_%04d.obj", frames);
  EXPECT_TRUE(fs::exists(out / "obj" / (example + last))) << "the last frame was not written";
}

INSTANTIATE_TEST_SUITE_P(EveryExample, ExampleBake, ::testing::ValuesIn(exampleNames()),
                         [](const auto& param) { return param.param; });

TEST(Version, PrintsTheVersion) {
  const Result run = runSoftbake("--version");
  EXPECT_EQ(run.exitCode, 0);
  EXPECT_EQ(run.output.rfind("softbake ", 0), 0u) << run.output;
}

TEST_F(CliTest, EveryBroadPhaseWritesTheSameBytesWithAndWithoutThePairCache) {
  // fig4's bodies touch from the first frames on, so the broad phases have contacts to agree on.
  const fs::path scene = examples() / "fig4_two_bodies.json";
  std::string reference;
  int variant = 0;
  for (const char* flags :
       {"--broadphase bvh", "--broadphase sbhash", "--broadphase spatialhash", "--broadphase brute",
        "--broadphase bvh --no-pair-cache", "--broadphase sbhash --no-pair-cache",
        "--broadphase spatialhash --no-pair-cache"}) {
    const fs::path out = folder_ / std::to_string(variant++);
    const Result run = runSoftbake("run " + quoted(scene.string()) + " --frames 30 -q " + flags +
                                   " -o " + quoted(out.string()));
    ASSERT_EQ(run.exitCode, 0) << flags << "\n" << run.output;
    const std::string frame = readFile(out / "obj/fig4_two_bodies_0030.obj") +
                              readFile(out / "contacts/fig4_two_bodies_0030.json");
    if (reference.empty()) reference = frame;
    EXPECT_TRUE(frame == reference) << flags << " differs from bvh with the pair cache";
  }
}

TEST_F(CliTest, ContactsAreWrittenPerFrameWhenAsked) {
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run --frames 14 --contacts -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  std::size_t contacts = 0;
  for (int frame = 1; frame <= 14; ++frame) {
    char name[64];
    std::snprintf(name, sizeof name, "contacts/default_%04d.json", frame);
    const nlohmann::json json = nlohmann::json::parse(readFile(out / name));
    EXPECT_EQ(json.at("frame").get<int>(), frame);
    for (const nlohmann::json& contact : json.at("contacts")) {
      ++contacts;
      EXPECT_EQ(contact.at("bodies").size(), 2u);
      EXPECT_EQ(contact.at("position").size(), 3u);
    }
  }
  EXPECT_GT(contacts, 0u) << "the default scene's balls meet by frame 14";
  const nlohmann::json manifest = nlohmann::json::parse(readFile(out / "manifest.json"));
  EXPECT_NE(manifest.dump().find("contacts/default_####.json"), std::string::npos);
}

// Figure 5 of the paper: one body and the ground. Its contacts are all with the plane; with the
// response they hold the ball up, and detection alone (figure 5b) still finds them.
TEST_F(CliTest, PlaneContactsAreWrittenWithAndWithoutResponse) {
  const fs::path scene = examples() / "fig5_ground.json";
  for (const bool respond : {true, false}) {
    const fs::path out = folder_ / (respond ? "respond" : "detect");
    const Result run =
        runSoftbake("run " + quoted(scene.string()) + " --frames 48 --contacts --no-render -q" +
                    (respond ? "" : " --response none") + " -o " + quoted(out.string()));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find("plane contacts"), std::string::npos) << run.output;
    std::size_t framesWithContacts = 0;
    for (int frame = 1; frame <= 48; ++frame) {
      char name[64];
      std::snprintf(name, sizeof name, "contacts/fig5_ground_%04d.json", frame);
      const nlohmann::json contacts = nlohmann::json::parse(readFile(out / name)).at("contacts");
      framesWithContacts += !contacts.empty();
      for (const nlohmann::json& contact : contacts) {
        EXPECT_EQ(contact.at("kind"), "plane");
        EXPECT_EQ(contact.at("bodies"), nlohmann::json::array({"ball", "ground"}));
        EXPECT_NEAR(contact.at("position")[1].get<double>(), 0, 1e-6) << "on the ground";
        EXPECT_TRUE(contact.at("particle").is_number_integer());
      }
    }
    // The ball falls 1.5 m to the ground in about 13 frames and touches it for three or four
    // frames at each bounce (or, without a response, goes on down through it).
    EXPECT_GT(framesWithContacts, 6u) << (respond ? "with" : "without") << " response";
  }
}

TEST_F(CliTest, NoResponseLetsTheBallFallThroughTheGround) {
  const fs::path scene = examples() / "fig5_ground.json";
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run " + quoted(scene.string()) +
                                 " --frames 24 --no-response -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  // The ball starts 2 m up and falls for a second: without a response it ends below the ground.
  const std::string obj = readFile(out / "obj/fig5_ground_0024.obj");
  double highest = -1e9;
  std::size_t begin = 0;
  while ((begin = obj.find("\nv ", begin)) != std::string::npos) {
    double x, y, z;
    std::sscanf(obj.c_str() + begin + 3, "%lf %lf %lf", &x, &y, &z);
    highest = std::max(highest, y);
    ++begin;
  }
  EXPECT_LT(highest, 0) << "with --no-response the whole ball passes the ground plane";
}

TEST_F(CliTest, ImplicitIntegratorRunsTheDefaultSceneInFewSubsteps) {
  const fs::path out = folder_ / "out";
  const Result run =
      runSoftbake("run --integrator implicit --frames 24 --no-render -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("implicit integrator"), std::string::npos) << run.output;
  EXPECT_TRUE(fs::exists(out / "obj/default_0024.obj"));
  const Result bad = runSoftbake("run --integrator verlet -o " + quoted(out.string()));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
  EXPECT_NE(bad.output.find("verlet"), std::string::npos) << bad.output;
}

TEST_F(CliTest, BodiesThatStartInsideEachOtherAreReportedWithWhatTheRunDoes) {
  const std::string bodies = R"("bodies": [
    {"name": "left", "mesh": {"primitive": "icosphere"}, "transform": {"translate": [-0.4, 1, 0]}},
    {"name": "right", "mesh": {"primitive": "icosphere"}, "transform": {"translate": [0.4, 1.03, 0.02]}}])";
  const fs::path separate =
      writeScene("separate.json", R"({"settings": {"frames": 2}, )" + bodies + "}");
  const Result run = runSoftbake("run " + quoted(separate.string()) + " --no-render -q -o " +
                                 quoted((folder_ / "s").string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("surfaces intersect at the start: 'left' and 'right' ("),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("triangle pairs are set aside until they come apart"),
            std::string::npos)
      << run.output;
  const fs::path glued = writeScene(
      "glued.json", R"({"settings": {"frames": 2, "collisions": {"initial_overlap": "ignore"}}, )" +
                        bodies + "}");
  const Result gluedRun = runSoftbake("run " + quoted(glued.string()) + " --no-render -q -o " +
                                      quoted((folder_ / "g").string()));
  ASSERT_EQ(gluedRun.exitCode, 0) << gluedRun.output;
  EXPECT_NE(gluedRun.output.find("never collide with each other"), std::string::npos)
      << gluedRun.output;
  const Result apart =
      runSoftbake("run --frames 2 --no-render -q -o " + quoted((folder_ / "d").string()));
  EXPECT_EQ(apart.output.find("intersect at the start"), std::string::npos) << apart.output;
}

/// A row of ten balls, each overlapping the next: nine pairs of surfaces, of which the warning
/// names the eight with the most triangle pairs and counts the rest, where an imported building
/// once printed 100 kB on one line.
TEST_F(CliTest, TheInitialOverlapWarningNamesTheLargestPairsAndCountsTheRest) {
  std::string bodies;
  for (int k = 0; k < 10; ++k)
    bodies += (k ? ", " : "") + std::string(R"({"name": "b)") + std::to_string(k) +
              R"(", "mesh": {"primitive": "icosphere"}, "transform": {"translate": [)" +
              std::to_string(0.8 * k) + ", 1, 0]}}";
  const fs::path scene =
      writeScene("row.json", R"({"settings": {"frames": 2}, "bodies": [)" + bodies + "]}");
  const Result run =
      runSoftbake("run " + quoted(scene.string()) + " --frames 1 --no-render -q -o " +
                  quoted((folder_ / "row").string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const std::size_t line = run.output.find("surfaces intersect at the start:");
  ASSERT_NE(line, std::string::npos) << run.output;
  const std::string warning = run.output.substr(line, run.output.find('\n', line) - line);
  int named = 0;
  for (std::size_t at = warning.find("' and '"); at != std::string::npos;
       at = warning.find("' and '", at + 1))
    ++named;
  EXPECT_EQ(named, 8) << warning;
  EXPECT_NE(warning.find(" and 1 more pairs of surfaces ("), std::string::npos) << warning;
}

TEST_F(CliTest, SceneKeyIntegratorIsReadAndCheckedWithItsPath) {
  const fs::path scene = writeScene("implicit.json", R"({"settings": {"integrator": "implicit",
    "frames": 3}, "bodies": [{"name": "ball", "mesh": {"primitive": "icosphere"}}]})");
  const Result run = runSoftbake("run " + quoted(scene.string()) + " --no-render -o " +
                                 quoted((folder_ / "o").string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("implicit integrator"), std::string::npos) << run.output;
  const fs::path badScene = writeScene("rk4.json", R"({"settings": {"integrator": "rk4"},
    "bodies": [{"name": "ball", "mesh": {"primitive": "icosphere"}}]})");
  const Result bad = runSoftbake("run " + quoted(badScene.string()) + " --no-render -o " +
                                 quoted((folder_ / "o2").string()));
  EXPECT_EQ(bad.exitCode, 1);
  EXPECT_NE(bad.output.find("settings.integrator"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("\"implicit\""), std::string::npos) << bad.output;
}

TEST_F(CliTest, UnknownBroadPhaseIsRefused) {
  const Result run = runSoftbake("run --broadphase octree -o " + quoted((folder_ / "o").string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("octree"), std::string::npos) << run.output;
}

// ---- Rendered frames against the committed golden frames (tests/golden) ----------------------

/// Renders `scene` (empty: the built-in one) at 320×240 for 120 frames into `out`.
void renderSmall(const std::string& scene, const fs::path& out) {
  const Result run =
      runSoftbake("run " + (scene.empty() ? std::string() : quoted(scene)) +
                  " --render --size 320x240 --frames 120 -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
}

/// `softbake compare GOLDEN RENDERED` by its default metric (flip, an edge may move by a pixel),
/// which other Mesa versions and GPUs pass (docs/regression.md).
int compareFrames(const fs::path& golden, const fs::path& rendered) {
  return runSoftbake("compare " + quoted(golden.string()) + " " + quoted(rendered.string()))
      .exitCode;
}

fs::path golden(const std::string& name) {
  return fs::path(SOFTBAKE_SOURCE_DIR) / "tests/golden" / name;
}

/// Compares rendered frames with their golden frames (`frames`: golden name → rendered file) as a
/// pipeline does: one `softbake compare` of two folders, with an HTML report and a JUnit file in
/// SOFTBAKE_TEST_ARTIFACTS_DIR/golden/`check`. When a frame differs they stay there and the
/// failure names them; when all pass the folder is removed.
void expectGoldenFrames(const std::string& check,
                        const std::vector<std::pair<std::string, fs::path>>& frames) {
  const fs::path work = fs::path(SOFTBAKE_TEST_ARTIFACTS_DIR) / "golden" / check;
  fs::remove_all(work);
  fs::create_directories(work / "golden");
  fs::create_directories(work / "rendered");
  for (const auto& [name, rendered] : frames) {
    fs::copy_file(golden(name), work / "golden" / name);
    fs::copy_file(rendered, work / "rendered" / name);
  }
  const Result run = runSoftbake("compare " + quoted((work / "golden").string()) + " " +
                                 quoted((work / "rendered").string()) + " --report " +
                                 quoted((work / "report").string()) + " --junit " +
                                 quoted((work / "junit.xml").string()));
  if (run.exitCode == 0) {
    fs::remove_all(work);
    return;
  }
  std::printf("golden frames differ: report %s, JUnit %s\n",
              (work / "report/index.html").string().c_str(), (work / "junit.xml").string().c_str());
  ADD_FAILURE() << "rendered frames differ from tests/golden; report: "
                << (work / "report/index.html").string()
                << ", JUnit: " << (work / "junit.xml").string() << "\n"
                << run.output;
}

class ContactExampleFrame : public CliTest,
                            public ::testing::WithParamInterface<std::pair<const char*, int>> {};

/// The hard contact cases (a ball on a pinned sheet, a mixed pile, a heavy ball on a jelly one,
/// parts that start inside each other, a folding flag), each at one frame where its contact shows,
/// against its golden frame.
TEST_P(ContactExampleFrame, MatchesItsGoldenFrame) {
  const auto [example, frame] = GetParam();
  const fs::path out = folder_ / example;
  const Result run =
      runSoftbake("run " + quoted((examples() / (std::string(example) + ".json")).string()) +
                  " --render --size 320x240 --frames " + std::to_string(frame) + " -q -o " +
                  quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  char name[64];
  std::snprintf(name, sizeof name, "%s_%04d.png", example, frame);
  expectGoldenFrames(example, {{name, out / "png" / name}});
}

INSTANTIATE_TEST_SUITE_P(HardCases, ContactExampleFrame,
                         ::testing::Values(std::pair("sheet_ball", 48), std::pair("mixed_pile", 48),
                                           std::pair("heavy_on_jelly", 36),
                                           std::pair("glued_assembly", 24),
                                           std::pair("flag_fold", 48)),
                         [](const auto& param) { return std::string(param.param.first); });

/// The negative control of the contact frames: the folding flag's frame rendered without its
/// contact spheres must fail against its golden frame, or the comparison could not see contacts go
/// missing.
TEST_F(CliTest, AContactFrameWithoutItsContactsFailsItsGoldenFrame) {
  const fs::path out = folder_ / "no_contacts";
  const Result run = runSoftbake(
      "run " + quoted((examples() / "flag_fold.json").string()) +
      " --render --size 320x240 --frames 48 --no-contact-spheres -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_EQ(compareFrames(golden("flag_fold_0048.png"), out / "png" / "flag_fold_0048.png"), 1)
      << "a frame without its contacts passed as the golden frame";
}

TEST_F(CliTest, RenderedFramesMatchTheGoldenFrames) {
  renderSmall("", folder_ / "default");
  renderSmall((examples() / "fig5_ground.json").string(), folder_ / "fig5");
  std::vector<std::pair<std::string, fs::path>> frames;
  for (const char* frame : {"0001", "0010", "0060", "0120"}) {
    const std::string name = std::string("default_") + frame + ".png";
    frames.emplace_back(name, folder_ / "default/png" / name);
  }
  for (const char* frame : {"0001", "0060", "0120"}) {
    const std::string name = std::string("fig5_ground_") + frame + ".png";
    frames.emplace_back(name, folder_ / "fig5/png" / name);
  }
  expectGoldenFrames("default_and_fig5", frames);
  // A change in what a frame shows must fail: the balls one frame further on in their flight, a
  // moved camera.
  EXPECT_EQ(compareFrames(golden("default_0010.png"), folder_ / "default/png/default_0011.png"), 1);
  nlohmann::json moved = nlohmann::json::parse(readFile(examples() / "default.json"));
  moved["render"] = {{"camera", {{"position", {1.0, 2.5, 7.0}}, {"target", {0.0, 1.0, 0.0}}}}};
  const fs::path movedScene = writeScene("default.json", moved.dump());
  const Result run =
      runSoftbake("run " + quoted(movedScene.string()) + " --size 320x240 --frames 1 -q -o " +
                  quoted((folder_ / "moved").string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_EQ(compareFrames(golden("default_0001.png"), folder_ / "moved/png/default_0001.png"), 1);
}

TEST_F(CliTest, RenderingIsByteIdenticalForOneAndTwoThreads) {
  for (const char* threads : {"1", "2"}) {
    const Result run = runSoftbake(std::string("run --render --size 160x120 --frames 12 -q -j ") +
                                   threads + " -o " + quoted((folder_ / threads).string()));
    ASSERT_EQ(run.exitCode, 0) << run.output;
  }
  EXPECT_TRUE(readFile(folder_ / "1/png/default_0012.png") ==
              readFile(folder_ / "2/png/default_0012.png"));
}

TEST_F(CliTest, NoRenderWritesNoFrames) {
  const Result run =
      runSoftbake("run --no-render --frames 2 -q -o " + quoted((folder_ / "o").string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_FALSE(fs::exists(folder_ / "o/png"));
}

TEST_F(CliTest, RendererStartFailureIsAClearError) {
  // An EGL platform that does not exist: the same path as a machine without a usable driver.
  const std::string command = "SOFTBAKE_EGL_PLATFORM=0x1234 " + std::string(SOFTBAKE_BINARY) +
                              " run --render --frames 2 -q -o " +
                              quoted((folder_ / "bad").string()) + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, read);
  const int status = pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << output;
  EXPECT_NE(output.find("libegl-mesa0"), std::string::npos) << output;
  EXPECT_NE(output.find("--no-render"), std::string::npos) << output;
  // Found before anything was written: no .mtl, no OBJ frame, no folder.
  EXPECT_FALSE(fs::exists(folder_ / "bad")) << output;
}

TEST_F(CliTest, VdbFramesAreWrittenAndListedInTheManifest) {
  const fs::path out = folder_ / "out";
  const Result run =
      runSoftbake("run --vdb --no-render --frames 2 --up z -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_GT(fs::file_size(out / "vdb/default_0002.vdb"), 1000u);
  const nlohmann::json manifest = nlohmann::json::parse(readFile(out / "manifest.json"));
  EXPECT_NE(manifest.dump().find("vdb/default_####.vdb"), std::string::npos);
}

TEST_F(CliTest, AVoxelSizeThatWouldNotFitInMemoryIsRefusedBeforeAnyWork) {
  const fs::path out = folder_ / "out";
  const Result run =
      runSoftbake("run --vdb --voxel-size 0.00001 --frames 2 -q -o " + quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("voxel"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(out)) << "nothing is written for bad settings";
}
