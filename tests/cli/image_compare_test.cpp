// Image regression: the per-pixel comparison, and `softbake compare` as pipelines call it.
#include "cli/image_compare.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;

Image gradient(int width, int height) {
  Image image{width, height, std::vector<std::uint8_t>(std::size_t(width) * height * 4)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = &image.rgba[4 * (std::size_t(y) * width + x)];
      p[0] = std::uint8_t(x * 255 / width);
      p[1] = std::uint8_t(y * 255 / height);
      p[2] = 128;
      p[3] = 255;
    }
  return image;
}

TEST(ImageCompare, IdenticalImagesMatchWithInfinitePsnr) {
  const Image a = gradient(32, 16);
  const ImageDifference d = compareImages(a, a, 0);
  EXPECT_EQ(d.pixels, 512u);
  EXPECT_EQ(d.pixelsOverTolerance, 0u);
  EXPECT_EQ(d.largestDifference, 0);
  EXPECT_TRUE(std::isinf(d.psnr));
}

TEST(ImageCompare, CountsPixelsOverTheToleranceAndMarksThemRed) {
  const Image a = gradient(32, 16);
  Image b = a;
  b.rgba[4 * 5 + 1] = std::uint8_t(b.rgba[4 * 5 + 1] + 40);  // pixel 5: +40 in green
  b.rgba[4 * 9 + 2] = std::uint8_t(b.rgba[4 * 9 + 2] + 3);   // pixel 9: +3, within tolerance
  Image diff;
  const ImageDifference d = compareImages(a, b, 8, &diff);
  EXPECT_EQ(d.pixelsOverTolerance, 1u);
  EXPECT_EQ(d.largestDifference, 40);
  // Mean squared error (40² + 3²)/(3·512): PSNR = 10·log10(255²/MSE).
  EXPECT_NEAR(d.psnr, 10 * std::log10(255.0 * 255.0 * 3 * 512 / (1600 + 9)), 1e-9);
  EXPECT_GT(diff.rgba[4 * 5], 128);
  EXPECT_EQ(diff.rgba[4 * 5 + 1], 0);
  EXPECT_EQ(diff.rgba[4 * 9], diff.rgba[4 * 9 + 1]) << "pixels within tolerance are grey";
}

TEST(ImageCompare, DifferentSizesAreAnError) {
  EXPECT_THROW(compareImages(gradient(8, 8), gradient(8, 9), 0), Error);
}

// ---- softbake compare, in a child process --------------------------------------------------

int exitCodeOf(const std::string& arguments, std::string* output = nullptr) {
  const std::string command = std::string(SOFTBAKE_BINARY) + " compare " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  char buffer[4096];
  std::size_t read = 0;
  std::string text;
  while ((read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) text.append(buffer, read);
  const int status = pclose(pipe);
  if (output) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class CompareCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() /
              (std::string("softbake_compare_") +
               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(folder_);
    fs::create_directories(folder_ / "a");
    fs::create_directories(folder_ / "b");
    for (int frame = 1; frame <= 3; ++frame) {
      const std::string name = "scene_000" + std::to_string(frame) + ".png";
      writePng(folder_ / "a" / name, gradient(40, 30));
      writePng(folder_ / "b" / name, gradient(40, 30));
    }
  }
  void TearDown() override { fs::remove_all(folder_); }
  std::string path(const std::string& relative) const { return (folder_ / relative).string(); }
  fs::path folder_;
};

TEST_F(CompareCommand, ExitCodesFollowTheContract) {
  EXPECT_EQ(exitCodeOf(path("a/scene_0001.png") + " " + path("b/scene_0001.png")), 0);
  Image changed = gradient(40, 30);
  for (std::size_t i = 0; i < 400 * 4; i += 4) changed.rgba[i] = 255;  // a third of the frame
  writePng(folder_ / "b/scene_0002.png", changed);
  std::string output;
  EXPECT_EQ(exitCodeOf(path("a/scene_0002.png") + " " + path("b/scene_0002.png") + " --diff " +
                           path("diff.png"),
                       &output),
            1)
      << output;
  EXPECT_TRUE(fs::exists(folder_ / "diff.png"));
  EXPECT_EQ(
      exitCodeOf(path("a/scene_0002.png") + " " + path("b/scene_0002.png") + " --max-fraction 0.5"),
      0)
      << "a third of the pixels is within a max fraction of one half";
  EXPECT_EQ(exitCodeOf(path("a/scene_0001.png") + " " + path("nope.png"), &output), 2);
  EXPECT_NE(output.find("nope.png"), std::string::npos) << output;
  writePng(folder_ / "small.png", gradient(20, 30));
  EXPECT_EQ(exitCodeOf(path("a/scene_0001.png") + " " + path("small.png"), &output), 2);
  EXPECT_NE(output.find("size"), std::string::npos) << output;
  EXPECT_EQ(
      exitCodeOf(path("a/scene_0001.png") + " " + path("b/scene_0001.png") + " --tolerance banana"),
      2);
}

TEST_F(CompareCommand, FoldersAreComparedFrameByFrame) {
  std::string output;
  EXPECT_EQ(exitCodeOf(path("a") + " " + path("b"), &output), 0) << output;
  EXPECT_NE(output.find("3 frames: 3 within bounds"), std::string::npos) << output;
  Image changed = gradient(40, 30);
  changed.rgba.assign(changed.rgba.size(), 255);
  writePng(folder_ / "b/scene_0003.png", changed);
  EXPECT_EQ(exitCodeOf(path("a") + " " + path("b") + " --diff " + path("diffs"), &output), 1);
  EXPECT_NE(output.find("scene_0003.png: DIFFERS"), std::string::npos) << output;
  EXPECT_TRUE(fs::exists(folder_ / "diffs/scene_0003.png"));
  fs::remove(folder_ / "b/scene_0002.png");
  EXPECT_EQ(exitCodeOf(path("a") + " " + path("b"), &output), 2);
  EXPECT_NE(output.find("scene_0002.png: missing"), std::string::npos) << output;
}

}  // namespace
}  // namespace softbake
