// The default metric on softbake's own frames: what must fail and what must pass
// (docs/regression.md has the measurements). One frame of the built-in scene at 320×240, the camera
// fixed close to the first ball so that it spans 200 pixels: 1% of its size is 2 pixels.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <string>

#include "tests/cli/softbake_process.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using test::quoted;
using test::runSoftbake;

class RenderedCompare : public test::CliTest {
 protected:
  /// Renders frame 1 of the built-in scene with `change` applied to its JSON; returns the PNG.
  fs::path render(const std::string& name, const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json scene = nlohmann::json::parse(
        test::readFile(fs::path(SOFTBAKE_SOURCE_DIR) / "examples/default.json"));
    scene["settings"]["frames"] = 1;
    // A fixed camera: an automatic one follows the bodies, and would move with the one moved.
    scene["render"] = {{"camera", {{"position", {-1.2, 1.6, 1.6}}, {"target", {-1.2, 1.5, 0.0}}}}};
    change(scene);
    const fs::path file = writeScene(name + ".json", scene.dump());
    const test::Result run =
        runSoftbake("run " + quoted(file) + " --size 320x240 --render --no-cache -q -o " +
                    quoted(folder_ / name));
    EXPECT_EQ(run.exitCode, 0) << run.output;
    return folder_ / name / "png/default_0001.png";
  }
  test::Result compare(const fs::path& a, const fs::path& b, const std::string& flags = "") {
    return runSoftbake("compare " + quoted(a) + " " + quoted(b) + " " + flags);
  }
};

TEST_F(RenderedCompare,
       ABodyMovedByOnePercentOfItsSizeFailsAndMultisamplingAndAPixelsCameraShiftPass) {
  const fs::path reference = render("reference", [](nlohmann::json&) {});  // 4 samples
  // The first ball (1 m across) 1 cm to the right; its first-frame size is its diameter.
  const fs::path moved = render("moved", [](nlohmann::json& s) {
    s["bodies"][0]["transform"]["translate"][0] = -1.2 + 0.01;
  });
  const test::Result movedRun = compare(reference, moved);
  EXPECT_EQ(movedRun.exitCode, 1) << movedRun.output;

  // Antialiasing: no multisampling, 8 and 16 samples (Mesa's llvmpipe offers 4 at most and
  // renders 8 and 16 as 4; a GPU renders them).
  for (const int samples : {1, 8, 16}) {
    const fs::path variant = render("samples" + std::to_string(samples),
                                    [&](nlohmann::json& s) { s["render"]["samples"] = samples; });
    const test::Result run = compare(reference, variant);
    EXPECT_EQ(run.exitCode, 0) << samples << " samples\n" << run.output;
  }
  // The camera one pixel to the right (at the target's distance: 2·1.6·tan 20° / 240 m), and half
  // a pixel: every edge moves by a pixel at most.
  for (const double pixels : {0.5, 1.0}) {
    const double shift = pixels * 2 * 1.6 * std::tan(20 * 3.14159265358979 / 180) / 240;
    const fs::path variant = render("camera" + std::to_string(pixels), [&](nlohmann::json& s) {
      s["render"]["camera"]["position"][0] = -1.2 + shift;
      s["render"]["camera"]["target"][0] = -1.2 + shift;
    });
    const test::Result run = compare(reference, variant);
    EXPECT_EQ(run.exitCode, 0) << "camera moved by " << pixels << " pixel\n" << run.output;
    // Pixel against pixel, the old way, the same shift fails: alignment is what forgives it.
    if (pixels == 1.0) {
      EXPECT_EQ(compare(reference, variant, "--align 0").exitCode, 1);
    }
  }
}

}  // namespace
}  // namespace softbake
