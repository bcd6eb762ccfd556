// Image regression: FLIP and the metrics in-process, and `softbake compare` on images as pipelines
// call it: exit codes, thresholds, folders, bad input and --update.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "cli/flip.hpp"
#include "cli/image_file.hpp"
#include "cli/image_metrics.hpp"
#include "core/error.hpp"
#include "tests/cli/softbake_process.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using test::quoted;
using test::readFile;
using test::runSoftbake;

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

/// A grey disc of `radius` at (cx, cy) on a dark background, antialiased by 4×4 supersampling.
ColorImage disc(int width, int height, double cx, double cy, double radius) {
  ColorImage image{width, height, std::vector<float>(3 * std::size_t(width) * height)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      int inside = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const double px = x + (sx + 0.5) / 4 - cx, py = y + (sy + 0.5) / 4 - cy;
          inside += px * px + py * py < radius * radius;
        }
      const float v = 0.1f + 0.7f * float(inside) / 16;
      for (int c = 0; c < 3; ++c) image.rgb[3 * (std::size_t(y) * width + x) + c] = v;
    }
  return image;
}

TEST(Flip, IdenticalImagesScoreZeroAndBlackAgainstWhiteNearlyOne) {
  const ColorImage a = toColorImage(gradient(24, 16));
  for (const FlipPixel& p : flipFeatures(a.rgb, a.width, a.height)) EXPECT_EQ(flipError(p, p), 0);
  const ColorImage black{16, 16, std::vector<float>(3 * 256, 0.0f)};
  const ColorImage white{16, 16, std::vector<float>(3 * 256, 1.0f)};
  const std::vector<FlipPixel> b = flipFeatures(black.rgb, 16, 16),
                               w = flipFeatures(white.rgb, 16, 16);
  // Black and white lie 100 apart in L*, against 0.95 of the scale at 0.4 of green–blue's
  // distance: an obvious difference, near the top of [0, 1].
  for (std::size_t p = 0; p < b.size(); ++p) {
    const float e = flipError(b[p], w[p]);
    EXPECT_GT(e, 0.9f);
    EXPECT_LE(e, 1.0f);
  }
}

TEST(ImageMetrics, AnEdgeMovedByOnePixelPassesAndByThreeFails) {
  const ColorImage reference = disc(64, 48, 30, 24, 14);
  const ImageThresholds flip = defaultThresholds(ImageMetric::Flip);
  EXPECT_EQ(compareImages(reference, disc(64, 48, 31, 24, 14), flip).verdict, Verdict::Pass);
  EXPECT_EQ(compareImages(reference, disc(64, 48, 30.4, 24.6, 14), flip).verdict, Verdict::Pass);
  const ImageComparison moved = compareImages(reference, disc(64, 48, 33, 24, 14), flip);
  EXPECT_EQ(moved.verdict, Verdict::Fail);
  EXPECT_GT(moved.statistics.overFail, 20u) << "both sides of the disc, top to bottom";
  ImageThresholds strict = flip;
  strict.align = 0;
  EXPECT_EQ(compareImages(reference, disc(64, 48, 31, 24, 14), strict).verdict, Verdict::Fail)
      << "without alignment a pixel's move is a difference";
}

TEST(ImageMetrics, ThePixelMetricCountsPixelsAboveItsFailValueAndTheHeatMapShowsThem) {
  const Image a = gradient(32, 16);
  Image b = a;
  b.rgba[4 * 5 + 1] = std::uint8_t(b.rgba[4 * 5 + 1] + 40);  // pixel 5: +40 in green
  b.rgba[4 * 9 + 2] = std::uint8_t(b.rgba[4 * 9 + 2] + 3);   // pixel 9: +3, within 8
  ImageThresholds pixel = defaultThresholds(ImageMetric::Pixel);
  pixel.align = 0;
  const ImageComparison d = compareImages(toColorImage(a), toColorImage(b), pixel);
  EXPECT_EQ(d.statistics.overFail, 1u);
  EXPECT_EQ(d.statistics.max, 40);
  EXPECT_EQ(d.verdict, Verdict::Fail) << "1 of 512 pixels is 0.2%, above 0.1%";
  // Mean squared error (40² + 3²)/(3·512): PSNR = 10·log10(255²/MSE).
  EXPECT_NEAR(d.psnr, 10 * std::log10(255.0 * 255.0 * 3 * 512 / (1600 + 9)), 1e-3);
  const Image heat = heatMap(toColorImage(a), d.map);
  EXPECT_GT(heat.rgba[4 * 5], heat.rgba[4 * 5 + 2] + 60) << "the changed pixel is red";
  EXPECT_EQ(heat.rgba[4 * 6], heat.rgba[4 * 6 + 1]) << "an unchanged pixel is grey";
}

TEST(ImageMetrics, DifferentSizesAreAnError) {
  EXPECT_THROW(compareImages(toColorImage(gradient(8, 8)), toColorImage(gradient(8, 9)),
                             defaultThresholds(ImageMetric::Flip)),
               Error);
}

/// `image` through OpenImageIO: EXR as linear half floats, TIFF as 16 bits.
void writeWithOpenImageIo(const fs::path& path, const ColorImage& image, bool linear) {
  std::vector<float> values = image.rgb;
  if (linear)
    for (float& v : values) v = srgbToLinear(v);
  auto out = OIIO::ImageOutput::create(path.string());
  ASSERT_TRUE(out) << path;
  OIIO::ImageSpec spec(image.width, image.height, 3,
                       linear ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT16);
  ASSERT_TRUE(out->open(path.string(), spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, values.data())) << out->geterror();
  out->close();
}

TEST(ImageFile, PngExrAndTiffOfOneFrameReadAlike) {
  test::ScratchDirectory folder;
  const ColorImage frame = disc(40, 30, 20, 15, 9);
  writePng(folder.path() / "frame.png", toImage(frame));
  writeWithOpenImageIo(folder.path() / "frame.exr", frame, true);
  writeWithOpenImageIo(folder.path() / "frame.tif", frame, false);
  const ColorImage png = readImage(folder.path() / "frame.png");
  for (const char* other : {"frame.exr", "frame.tif"}) {
    const ColorImage read = readImage(folder.path() / other);
    ASSERT_EQ(read.rgb.size(), png.rgb.size()) << other;
    for (std::size_t i = 0; i < png.rgb.size(); ++i)
      ASSERT_NEAR(read.rgb[i], png.rgb[i], 1.0 / 255) << other << " value " << i;
  }
}

// ---- softbake compare, in a child process --------------------------------------------------

class CompareCommand : public test::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    fs::create_directories(folder_ / "a");
    fs::create_directories(folder_ / "b");
    for (int frame = 1; frame <= 3; ++frame) {
      const std::string name = "scene_000" + std::to_string(frame) + ".png";
      writePng(folder_ / "a" / name, gradient(40, 30));
      writePng(folder_ / "b" / name, gradient(40, 30));
    }
  }
  std::string path(const std::string& relative) const { return quoted(folder_ / relative); }
  test::Result compare(const std::string& arguments) { return runSoftbake("compare " + arguments); }
};

TEST_F(CompareCommand, ExitCodesFollowTheContract) {
  EXPECT_EQ(compare(path("a/scene_0001.png") + " " + path("b/scene_0001.png")).exitCode, 0);
  Image changed = gradient(40, 30);
  for (std::size_t i = 0; i < 400 * 4; i += 4) changed.rgba[i] = 255;  // a third of the frame
  writePng(folder_ / "b/scene_0002.png", changed);
  test::Result run = compare(path("a/scene_0002.png") + " " + path("b/scene_0002.png") +
                             " --diff " + path("diff.png"));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_TRUE(fs::exists(folder_ / "diff.png"));
  run = compare(path("a/scene_0002.png") + " " + path("b/scene_0002.png") +
                " --tolerance 8 --max-fraction 0.5");
  EXPECT_EQ(run.exitCode, 0) << "a third of the pixels is within a max fraction of one half\n"
                             << run.output;
  run = compare(path("a/scene_0001.png") + " " + path("nope.png"));
  EXPECT_EQ(run.exitCode, 2);
  EXPECT_NE(run.output.find("nope.png: no such file"), std::string::npos) << run.output;
  EXPECT_EQ(
      compare(path("a/scene_0001.png") + " " + path("b/scene_0001.png") + " --tolerance banana")
          .exitCode,
      2);
}

TEST_F(CompareCommand, FoldersAreMatchedFrameByFrameAndAMissingOrExtraFrameFailsNamed) {
  test::Result run = compare(path("a") + " " + path("b"));
  EXPECT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("3 frames: 3 within bounds"), std::string::npos) << run.output;
  Image changed = gradient(40, 30);
  changed.rgba.assign(changed.rgba.size(), 255);
  writePng(folder_ / "b/scene_0003.png", changed);
  run = compare(path("a") + " " + path("b") + " --diff " + path("diffs"));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("scene_0003.png: DIFFERS"), std::string::npos) << run.output;
  EXPECT_TRUE(fs::exists(folder_ / "diffs/scene_0003.png"));
  EXPECT_FALSE(fs::exists(folder_ / "diffs/scene_0001.png")) << "only frames that differ";
  fs::remove(folder_ / "b/scene_0003.png");
  fs::remove(folder_ / "b/scene_0002.png");
  writePng(folder_ / "b/scene_0004.png", gradient(40, 30));
  run = compare(path("a") + " " + path("b"));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("scene_0002.png: DIFFERS: missing in"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("scene_0004.png: DIFFERS: not in the reference folder"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("3 differ (3 of them missing)"), std::string::npos) << run.output;
}

TEST_F(CompareCommand, AnExrReferenceStandsForThePngFrameOfItsName) {
  fs::create_directories(folder_ / "exr");
  const ColorImage frame = toColorImage(gradient(40, 30));
  for (int f = 1; f <= 3; ++f)
    writeWithOpenImageIo(folder_ / ("exr/scene_000" + std::to_string(f) + ".exr"), frame, true);
  const test::Result run = compare(path("exr") + " " + path("b"));
  EXPECT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("scene_0001.exr: ok"), std::string::npos) << run.output;
}

TEST_F(CompareCommand, BadInputIsExitTwoWithTheFileAndTheProblemNamed) {
  const auto expectBadInput = [&](const std::string& arguments, const std::string& message) {
    const test::Result run = compare(arguments);
    EXPECT_EQ(run.exitCode, 2) << arguments << "\n" << run.output;
    EXPECT_NE(run.output.find(message), std::string::npos) << arguments << "\n" << run.output;
  };
  writePng(folder_ / "small.png", gradient(20, 30));
  expectBadInput(path("a/scene_0001.png") + " " + path("small.png"),
                 "small.png: the images differ in size: 40x30 and 20x30");
  // A PNG cut short in its pixel data: the reader must say so, not compare what it got.
  const std::string whole = readFile(folder_ / "a/scene_0001.png");
  std::ofstream(folder_ / "b/scene_0001.png", std::ios::binary)
      << whole.substr(0, whole.size() / 2);
  expectBadInput(path("a") + " " + path("b"), "scene_0001.png: cannot read the image");
  fs::create_directories(folder_ / "empty");
  expectBadInput(path("a") + " " + path("empty"), "empty: no frames (PNG, EXR, TIFF or JPEG)");
  expectBadInput(path("a") + " " + path("a/scene_0002.png"), "not one of each");
  expectBadInput(
      path("a/scene_0002.png") + " " + path("a/scene_0003.png") + " --metric flip --tolerance 4",
      "--tolerance and --max-fraction are the pixel metric's thresholds");
}

TEST_F(CompareCommand, EachMetricHasItsFailAndWarnThresholds) {
  // A fifth of the frame a little brighter: a broad, faint change.
  Image brighter = gradient(40, 30);
  for (std::size_t p = 0; p < 240; ++p)
    for (std::size_t c = 0; c < 3; ++c)
      brighter.rgba[4 * p + c] = std::uint8_t(std::min(255, brighter.rgba[4 * p + c] + 6));
  writePng(folder_ / "b/scene_0001.png", brighter);
  const std::string pair = path("a/scene_0001.png") + " " + path("b/scene_0001.png");
  const auto verdict = [&](const std::string& flags) {
    const test::Result run = compare(pair + " " + flags);
    return std::to_string(run.exitCode) +
           (run.output.find(": warn:") != std::string::npos ? " warn" : "");
  };
  EXPECT_EQ(verdict("--metric pixel"), "0") << "6 of 255 is within the default 8";
  EXPECT_EQ(verdict("--metric pixel --fail 5 --fail-percent 10"), "1");
  EXPECT_EQ(
      verdict("--metric pixel --align 1 --fail 5 --fail-percent 30 --warn 5 --warn-percent 10"),
      "0 warn")
      << "alignment forgives a moved edge, not a brighter area";
  EXPECT_EQ(verdict("--metric flip --fail-mean 0.001"), "1");
  EXPECT_EQ(
      verdict("--metric flip --fail 0.5 --fail-mean 1 --warn 0.01 --warn-percent 5 --warn-mean 1"),
      "0 warn");
  EXPECT_EQ(verdict("--metric yee --fail-percent 100"), "0");
}

TEST_F(CompareCommand, UpdateAcceptsTheNewFramesAndThenComparePasses) {
  Image changed = gradient(40, 30);
  changed.rgba.assign(changed.rgba.size(), 200);
  writePng(folder_ / "b/scene_0002.png", changed);
  fs::remove(folder_ / "b/scene_0003.png");
  writePng(folder_ / "b/scene_0004.png", gradient(40, 30));
  const std::string untouched = readFile(folder_ / "a/scene_0001.png");
  const auto modified = fs::last_write_time(folder_ / "a/scene_0001.png");
  test::Result run = compare(path("a") + " " + path("b") + " --update");
  EXPECT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("scene_0002.png: DIFFERS"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("3 files changed"), std::string::npos) << run.output;
  EXPECT_EQ(readFile(folder_ / "a/scene_0002.png"), readFile(folder_ / "b/scene_0002.png"));
  EXPECT_FALSE(fs::exists(folder_ / "a/scene_0003.png")) << "the new frames lack it";
  EXPECT_TRUE(fs::exists(folder_ / "a/scene_0004.png"));
  EXPECT_EQ(fs::last_write_time(folder_ / "a/scene_0001.png"), modified) << "it passed: left alone";
  EXPECT_EQ(readFile(folder_ / "a/scene_0001.png"), untouched);
  run = compare(path("a") + " " + path("b"));
  EXPECT_EQ(run.exitCode, 0) << run.output;
}

TEST_F(CompareCommand, AnInterruptedUpdateLeavesEveryReferenceWholeOldOrNew) {
  // Three new frames: small, then one too big for the file-size limit below, then small. The
  // update is cut off at the second, as a full disk or a kill would cut it.
  Image noise{200, 200, std::vector<std::uint8_t>(200 * 200 * 4)};
  std::uint32_t state = 12345;
  for (std::uint8_t& byte : noise.rgba)
    byte = std::uint8_t((state = state * 1103515245 + 12345) >> 24);
  Image flat = gradient(40, 30);
  flat.rgba.assign(flat.rgba.size(), 90);
  writePng(folder_ / "b/scene_0001.png", flat);
  writePng(folder_ / "b/scene_0002.png", Image{200, 200, noise.rgba});
  writePng(folder_ / "b/scene_0003.png", flat);
  fs::create_directories(folder_ / "a2");
  for (const char* name : {"scene_0001.png", "scene_0003.png"})
    fs::copy(folder_ / "a" / name, folder_ / "a2" / name);
  writePng(folder_ / "a2/scene_0002.png",
           Image{200, 200, std::vector<std::uint8_t>(200 * 200 * 4, 255)});
  const std::string old2 = readFile(folder_ / "a2/scene_0002.png"),
                    old3 = readFile(folder_ / "a2/scene_0003.png");
  ASSERT_GT(readFile(folder_ / "b/scene_0002.png").size(), 100000u);
  // ulimit -f counts 1024-byte blocks in bash: 64 KiB.
  const std::string command =
      "bash -c " +
      quoted("ulimit -f 64; exec " + std::string(SOFTBAKE_BINARY) + " compare " +
             (folder_ / "a2").string() + " " + (folder_ / "b").string() + " --update 2>&1");
  const test::Result cut = test::runShell(command);
  const std::string& output = cut.output;
  EXPECT_EQ(cut.exitCode, 2) << output;
  EXPECT_NE(output.find("scene_0002.png"), std::string::npos) << output;
  EXPECT_EQ(readFile(folder_ / "a2/scene_0001.png"), readFile(folder_ / "b/scene_0001.png"))
      << "written before the cut";
  EXPECT_EQ(readFile(folder_ / "a2/scene_0002.png"), old2) << "the cut one is whole: the old one";
  EXPECT_EQ(readFile(folder_ / "a2/scene_0003.png"), old3) << "never reached";
  for (const std::string& name : test::listDirectory(folder_ / "a2"))
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << "a temporary file left: " << name;
  const test::Result again = compare(path("a2") + " " + path("b") + " --update");
  EXPECT_EQ(again.exitCode, 0) << again.output;
  EXPECT_EQ(compare(path("a2") + " " + path("b")).exitCode, 0);
}

}  // namespace
}  // namespace softbake
