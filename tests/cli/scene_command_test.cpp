// `softbake scene`, run as a child process like bench/blender_peer.sh runs it: the JSON it prints
// must parse, describe the scene, and load back into softbake as a scene file.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "softbake_process.hpp"

namespace fs = std::filesystem;

namespace {

using softbake::test::Result;
using softbake::test::runSoftbake;

/// A fresh folder per test under the system temp folder, removed afterwards.
class SceneCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = fs::temp_directory_path() / (std::string("softbake_scene_") + info->name());
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  fs::path folder_;
};

}  // namespace

TEST_F(SceneCommandTest, BuiltInSceneJsonParsesAndRunsBackAsAFile) {
  const Result printed = runSoftbake("scene balls10k", false);
  ASSERT_EQ(printed.exitCode, 0) << printed.output;
  const nlohmann::json scene = nlohmann::json::parse(printed.output);
  EXPECT_EQ(scene.at("name").get<std::string>(), "balls10k");
  ASSERT_EQ(scene.at("bodies").size(), 8u);

  const fs::path file = folder_ / "balls10k.json";
  std::ofstream(file) << printed.output;
  const Result bench = runSoftbake("bench '" + file.string() + "' --steps 2", true);
  ASSERT_EQ(bench.exitCode, 0) << bench.output;
  EXPECT_NE(bench.output.find("scene=balls10k faces=10240 "), std::string::npos) << bench.output;
}

TEST_F(SceneCommandTest, SceneFileIsPrintedAsParsed) {
  const fs::path file = folder_ / "commented.json";
  std::ofstream(file) << R"({
    // a comment the printed JSON drops
    "name": "one", "bodies": [{"mesh": {"primitive": "icosphere", "subdivisions": 1}}]})";
  const Result printed = runSoftbake("scene '" + file.string() + "'", false);
  ASSERT_EQ(printed.exitCode, 0) << printed.output;
  const nlohmann::json scene = nlohmann::json::parse(printed.output);
  EXPECT_EQ(scene.at("bodies").at(0).at("mesh").at("subdivisions").get<int>(), 1);
}

TEST_F(SceneCommandTest, UnknownNameFailsNamingIt) {
  const Result printed = runSoftbake("scene balls7k", true);
  EXPECT_EQ(printed.exitCode, 1) << printed.output;
  EXPECT_NE(printed.output.find("balls7k"), std::string::npos) << printed.output;
}
