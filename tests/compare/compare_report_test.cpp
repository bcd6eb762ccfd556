// What `softbake compare` leaves for CI: the JUnit file, read by Python's XML parser, and the HTML
// report, opened by Debian's chromium from disk with the network off (check_report.py). The
// screenshot stays in SOFTBAKE_TEST_ARTIFACTS_DIR/compare_report.png for a person to look at.
#include <gtest/gtest.h>

#include <string>

#include "cli/image_file.hpp"
#include "tests/compare/check_report.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using test::checkReport;
using test::quoted;
using test::runSoftbake;

Image filled(int width, int height, std::uint8_t value) {
  return {width, height, std::vector<std::uint8_t>(std::size_t(width) * height * 4, value)};
}

/// A grey frame with a square of `brightness` at `left`: squares that moved are what differs.
Image square(int left, std::uint8_t brightness = 230) {
  Image image = filled(48, 32, 60);
  for (int y = 8; y < 24; ++y)
    for (int x = left; x < left + 16; ++x)
      for (int c = 0; c < 3; ++c) image.rgba[4 * (std::size_t(y) * 48 + x) + c] = brightness;
  return image;
}

class CompareReport : public test::CliTest {
 protected:
  /// Reference and new frames: 3 the same, 1 with its square moved by 1 pixel (passes), 1 with it
  /// a little dimmer all over (warns), 2 with it moved by 6 pixels (fail), 1 dropped, 1 added.
  void SetUp() override {
    CliTest::SetUp();
    fs::create_directories(folder_ / "reference");
    fs::create_directories(folder_ / "new");
    const auto frame = [&](int number, const Image& reference, const Image* candidate) {
      char name[32];
      std::snprintf(name, sizeof name, "shot_%04d.png", number);
      if (number != 9) writePng(folder_ / "reference" / name, reference);
      if (candidate) writePng(folder_ / "new" / name, *candidate);
    };
    const Image same = square(10), nudged = square(11), moved = square(16),
                dimmer = square(10, 221);
    for (int f = 1; f <= 3; ++f) frame(f, same, &same);
    frame(4, same, &nudged);
    frame(5, same, &dimmer);
    frame(6, same, &moved);
    frame(7, same, &moved);
    frame(8, same, nullptr);
    frame(9, same, &same);
  }
};

TEST_F(CompareReport, JunitHoldsACasePerFrameAndAFailurePerFrameThatDiffers) {
  const fs::path junit = folder_ / "ci/junit.xml";
  const test::Result run = runSoftbake("compare " + quoted(folder_ / "reference") + " " +
                                       quoted(folder_ / "new") + " --junit " + quoted(junit));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("9 frames: 5 within bounds (1 warn), 4 differ (2 of them missing)"),
            std::string::npos)
      << run.output;
  const test::Result check = checkReport("junit " + quoted(junit) + " 9 4");
  EXPECT_EQ(check.exitCode, 0) << check.output;
  const std::string xml = test::readFile(junit);
  EXPECT_NE(xml.find("<testcase classname=\"softbake.compare.images\" name=\"shot_0006.png\">\n"
                     "      <failure message=\"flip: mean"),
            std::string::npos)
      << xml;
}

TEST_F(CompareReport, TheReportOpensOfflineInChromiumWithARowPerFrameFailuresFirst) {
  const fs::path report = folder_ / "report";
  const test::Result run = runSoftbake("compare " + quoted(folder_ / "reference") + " " +
                                       quoted(folder_ / "new") + " --report " + quoted(report));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("report: " + (report / "index.html").string()), std::string::npos)
      << run.output;
  // Moved elsewhere, as CI's artifacts are: the folder holds everything it shows.
  const fs::path moved = folder_ / "artifacts/report";
  fs::create_directories(moved.parent_path());
  fs::rename(report, moved);
  const fs::path screenshot = fs::path(SOFTBAKE_TEST_ARTIFACTS_DIR) / "compare_report.png";
  const test::Result check = checkReport("browser " + quoted(moved) + " 9 " + quoted(screenshot));
  EXPECT_EQ(check.exitCode, 0) << check.output;
  EXPECT_GT(fs::file_size(screenshot), 1000u);
  const std::string html = test::readFile(moved / "index.html");
  EXPECT_NE(html.find("4 of 9 frames differ, 1 warn"), std::string::npos) << html;
}

}  // namespace
}  // namespace softbake
