// The default metric on softbake's own frames: what must fail and what must pass
// (docs/regression.md has the measurements). One frame of the built-in scene at 320×240, the camera
// fixed close to the first ball so that it spans 200 pixels: 1% of its size is 2 pixels.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tests/cli/softbake_process.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using test::quoted;
using test::runSoftbake;

class RenderedCompare : public test::CliTest {
 protected:
  using Change = std::function<void(nlohmann::json&)>;
  /// Renders frame 1 of the built-in scene once per variant, `change` applied to its JSON, two at
  /// a time; returns each variant's PNG by name.
  std::map<std::string, fs::path> render(
      const std::vector<std::pair<std::string, Change>>& variants) {
    std::string commands;
    std::map<std::string, fs::path> frames;
    for (const auto& [name, change] : variants) {
      nlohmann::json scene = nlohmann::json::parse(
          test::readFile(fs::path(SOFTBAKE_SOURCE_DIR) / "examples/default.json"));
      scene["settings"]["frames"] = 1;
      // A fixed camera: an automatic one follows the bodies, and would move with the one moved.
      scene["render"] = {
          {"camera", {{"position", {-1.2, 1.6, 1.6}}, {"target", {-1.2, 1.5, 0.0}}}}};
      change(scene);
      const fs::path file = writeScene(name + ".json", scene.dump());
      commands += quoted(fs::path(SOFTBAKE_BINARY).string()) + " run " + quoted(file) +
                  " --size 320x240 --render --no-cache -q -o " + quoted(folder_ / name) +
                  " >/dev/null 2>&1 || echo 'render failed: " + name + "'\n";
      frames[name] = folder_ / name / "png/default_0001.png";
    }
    // One command a line; xargs runs two at once, each line whole (with -d, quotes are the
    // shell's).
    const fs::path list = writeScene("renders.txt", commands);
    const test::Result run =
        test::runShell("xargs -P 2 -d '\\n' -I{} sh -c {} < " + test::quoted(list));
    EXPECT_EQ(run.output.find("render failed"), std::string::npos) << run.output;
    return frames;
  }
  test::Result compare(const fs::path& a, const fs::path& b, const std::string& flags = "") {
    return runSoftbake("compare " + quoted(a) + " " + quoted(b) + " " + flags);
  }
};

TEST_F(RenderedCompare,
       ABodyMovedByOnePercentOfItsSizeFailsAndMultisamplingAndAPixelsCameraShiftPass) {
  // The camera moved to the right by `pixels` at the target's distance (2·1.6·tan 20° / 240 m a
  // pixel): every edge moves by that much at most.
  const auto camera = [](double pixels) {
    return [pixels](nlohmann::json& s) {
      const double shift = pixels * 2 * 1.6 * std::tan(20 * 3.14159265358979 / 180) / 240;
      s["render"]["camera"]["position"][0] = -1.2 + shift;
      s["render"]["camera"]["target"][0] = -1.2 + shift;
    };
  };
  std::map<std::string, fs::path> frame = render({
      {"reference", [](nlohmann::json&) {}},  // 4 samples
      // The first ball (1 m across) 1 cm to the right; its first-frame size is its diameter.
      {"moved",
       [](nlohmann::json& s) { s["bodies"][0]["transform"]["translate"][0] = -1.2 + 0.01; }},
      // Antialiasing: none, and 8 samples (Mesa's llvmpipe offers 4 at most and renders 8 as 4; a
      // GPU renders them).
      {"samples1", [](nlohmann::json& s) { s["render"]["samples"] = 1; }},
      {"samples8", [](nlohmann::json& s) { s["render"]["samples"] = 8; }},
      {"camera_half_pixel", camera(0.5)},
      {"camera_1_pixel", camera(1)},
  });
  const fs::path reference = frame["reference"];
  const test::Result moved = compare(reference, frame["moved"]);
  EXPECT_EQ(moved.exitCode, 1) << moved.output;
  for (const char* name : {"samples1", "samples8", "camera_half_pixel", "camera_1_pixel"}) {
    const test::Result run = compare(reference, frame[name]);
    EXPECT_EQ(run.exitCode, 0) << name << "\n" << run.output;
  }
  // Pixel against pixel, the old way, the camera moved by a pixel fails: alignment forgives it.
  EXPECT_EQ(compare(reference, frame["camera_1_pixel"], "--align 0").exitCode, 1);
}

}  // namespace
}  // namespace softbake
