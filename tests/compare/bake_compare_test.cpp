// `softbake compare OUT_A OUT_B` on two bakes: their caches, or OBJ sequences. The built-in scene,
// 10 frames without rendering: the balls meet at frame 8, so a change shows within the run.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <functional>
#include <string>

#include "tests/compare/check_report.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using test::quoted;
using test::runSoftbake;

class BakeCompare : public test::CliTest {
 protected:
  /// Bakes the built-in scene with `change` applied to its JSON into folder_/`name`.
  fs::path bake(const std::string& name, const std::function<void(nlohmann::json&)>& change,
                const std::string& flags = "") {
    nlohmann::json scene = nlohmann::json::parse(
        test::readFile(fs::path(SOFTBAKE_SOURCE_DIR) / "examples/default.json"));
    scene["settings"]["frames"] = 10;
    scene["output"]["png"] = false;
    change(scene);
    const fs::path file = writeScene(name + ".json", scene.dump());
    const test::Result run =
        runSoftbake("run " + quoted(file) + " -q " + flags + " -o " + quoted(folder_ / name));
    EXPECT_EQ(run.exitCode, 0) << run.output;
    return folder_ / name;
  }
  test::Result compare(const fs::path& a, const fs::path& b, const std::string& flags = "") {
    return runSoftbake("compare " + quoted(a) + " " + quoted(b) + " " + flags);
  }
};

TEST_F(BakeCompare, OneSceneBakedTwiceMatchesExactly) {
  const fs::path a = bake("a", [](nlohmann::json&) {}), b = bake("b", [](nlohmann::json&) {});
  const test::Result run = compare(a, b);
  EXPECT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("10 items: 10 within bounds (0 warn), 0 differ"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("frame 10: ok: identical in every body"), std::string::npos)
      << run.output;
}

TEST_F(BakeCompare, AMaterialChangeFailsNamingTheBodyAndTheFrameWhereItFirstExceeds) {
  const fs::path a = bake("a", [](nlohmann::json&) {});
  // ballB a little stiffer: it flies the same until the balls meet.
  const fs::path b = bake("b", [](nlohmann::json& s) {
    s["bodies"][1]["material"] = {{"preset", "rubber"}, {"stiffness", 2200}};
  });
  const fs::path report = folder_ / "report", junit = folder_ / "junit.xml";
  test::Result run = compare(a, b, "--report " + quoted(report) + " --junit " + quoted(junit));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("ballB: first over a threshold at frame "), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("frame 1: ok"), std::string::npos) << run.output;
  // The report plots displacement, volume and contacts; the JUnit file has a case per frame.
  const std::string html = test::readFile(report / "index.html");
  std::size_t plots = 0;
  for (std::size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1))
    ++plots;
  EXPECT_EQ(plots, 3u);
  EXPECT_NE(html.find("ballB: first over a threshold at frame"), std::string::npos);
  std::size_t failing = 0;
  for (std::size_t at = run.output.find(": DIFFERS: "); at != std::string::npos;
       at = run.output.find(": DIFFERS: ", at + 1))
    ++failing;
  EXPECT_GT(failing, 0u);
  const test::Result check =
      test::checkReport("junit " + quoted(junit) + " 10 " + std::to_string(failing));
  EXPECT_EQ(check.exitCode, 0) << check.output;
  // The same, forgiven by thresholds wide enough; a contact count that changes stays a failure
  // until its own threshold is raised.
  run = compare(a, b,
                "--max-distance 10 --max-rms 10 --max-volume-change 10 --max-contact-change 100");
  EXPECT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find(": warn: "), std::string::npos) << "changed, within bounds\n"
                                                            << run.output;
}

TEST_F(BakeCompare, ADroppedFrameFailsNamingIt) {
  const fs::path a = bake("a", [](nlohmann::json&) {}), b = bake("b", [](nlohmann::json&) {});
  fs::remove(b / "cache/default_0004.sbframe");
  test::Result run = compare(a, b);
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("frame 4: DIFFERS: frame 4 is missing in the new bake"),
            std::string::npos)
      << run.output;
  const fs::path shorter = bake("short", [](nlohmann::json& s) { s["settings"]["frames"] = 9; });
  run = compare(a, shorter);
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("frame 10 is missing in the new bake"), std::string::npos)
      << run.output;
}

TEST_F(BakeCompare, ObjSequencesCompareAsCachesDoAndATopologyChangeFails) {
  const fs::path a = bake("a", [](nlohmann::json&) {}), b = bake("b", [](nlohmann::json&) {});
  fs::remove_all(b / "cache");
  test::Result run = compare(a / "obj", b / "obj");
  EXPECT_EQ(run.exitCode, 0) << run.output;
  run = compare(a, b / "obj");
  EXPECT_EQ(run.exitCode, 0) << "a cache against an OBJ sequence\n" << run.output;
  // One face of ballA turned over in every frame of B: same particles, other triangles.
  for (const fs::directory_entry& entry : fs::directory_iterator(b / "obj")) {
    if (entry.path().extension() != ".obj") continue;
    std::string text = test::readFile(entry.path());
    const std::size_t face = text.find("\nf ");
    const std::size_t end = text.find('\n', face + 1);
    std::string line = text.substr(face + 3, end - face - 3);  // "1//1 2//2 3//3"
    const std::size_t gap = line.find(' ');
    const std::size_t gap2 = line.find(' ', gap + 1);
    line = line.substr(0, gap) + " " + line.substr(gap2 + 1) + " " +
           line.substr(gap + 1, gap2 - gap - 1);
    text.replace(face + 3, end - face - 3, line);
    std::ofstream(entry.path()) << text;
  }
  run = compare(a, b / "obj");
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(
      run.output.find("topology of ballA: DIFFERS: the body's topology changed: 642 particles "
                      "and 1280 triangles, then 642 and 1280 with other triangles"),
      std::string::npos)
      << run.output;
}

TEST_F(BakeCompare, BakesOfDifferentScenesAreBadInput) {
  const fs::path a = bake("a", [](nlohmann::json&) {});
  const fs::path other = bake("other", [](nlohmann::json& s) {
    s["bodies"] = nlohmann::json::array({s["bodies"][0]});
    s["bodies"][0]["name"] = "ball";
  });
  test::Result run = compare(a, other);
  EXPECT_EQ(run.exitCode, 2) << run.output;
  EXPECT_NE(run.output.find("these are bakes of different scenes"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("has 'ball'"), std::string::npos) << run.output;
  fs::create_directories(folder_ / "pictures");
  std::ofstream(folder_ / "pictures/frame.png") << "not a bake";
  run = compare(a, folder_ / "pictures");
  EXPECT_EQ(run.exitCode, 2) << run.output;
  EXPECT_NE(run.output.find("not one of each"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace softbake
