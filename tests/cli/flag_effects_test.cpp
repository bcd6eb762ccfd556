// The effect of the flags no other test had reached, each through the binary and checked by what
// it changes: --render-while-simulating frames the first frame, bench --with-exports times and
// keeps the writers' files, -j gives the same bytes with one thread as with two, -q leaves only
// the summary, wedge --parallel bakes the same variants, farm --cpus-per-task reaches sbatch.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "tests/cli/softbake_process.hpp"

namespace softbake::test {
namespace {

namespace fs = std::filesystem;

// A ball thrown sideways along the ground: over the shot it travels about three of its sizes.
constexpr const char* kThrownBall = R"({
  "name": "thrown",
  "settings": { "fps": 24, "frames": 12 },
  "bodies": [
    { "name": "ball", "mesh": { "primitive": "icosphere", "subdivisions": 2, "radius": 0.3 },
      "transform": { "translate": [0, 0.35, 0] }, "velocity": [4, 0, 0] }
  ],
  "colliders": [ { "type": "plane", "name": "ground" } ]
})";

std::map<std::string, std::string> filesUnder(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder))
    if (entry.is_regular_file())
      files[fs::relative(entry.path(), folder).string()] = readFile(entry.path());
  return files;
}

class FlagEffects : public CliTest {};

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST_F(FlagEffects, RenderWhileSimulatingFramesTheFirstFrameNotTheWholeShot) {
  const fs::path scene = writeScene("thrown.json", kThrownBall);
  for (const char* mode : {"after", "while"}) {
    const Result run = runSoftbake(
        "run " + quoted(scene) + " --render --size 160x90 -q -o " + quoted(folder_ / mode) +
        (std::string(mode) == "while" ? " --render-while-simulating" : ""));
    ASSERT_EQ(run.exitCode, 0) << run.output;
  }
  const auto after = filesUnder(folder_ / "after" / "png");
  const auto during = filesUnder(folder_ / "while" / "png");
  ASSERT_EQ(after.size(), 12u);
  ASSERT_EQ(during.size(), 12u);
  // Framed on the first frame only, the camera sits closer: the same simulated frame looks
  // different.
  EXPECT_NE(after.at("thrown_0001.png"), during.at("thrown_0001.png"));
  // The simulation is the same either way.
  EXPECT_EQ(filesUnder(folder_ / "after" / "obj"), filesUnder(folder_ / "while" / "obj"));
}

TEST_F(FlagEffects, BenchWithExportsTimesEveryWriterAndKeepsItsFilesInOut) {
  const Result plain = runSoftbake("bench default --frames 3 -j 1");
  ASSERT_EQ(plain.exitCode, 0) << plain.output;
  EXPECT_FALSE(has(plain.output, "export obj")) << plain.output;
  EXPECT_TRUE(has(plain.output, " threads=1 ")) << plain.output;

  const fs::path out = folder_ / "exports";
  const Result exporting =
      runSoftbake("bench default --frames 3 --with-exports -o " + quoted(out) + " --threads 2");
  ASSERT_EQ(exporting.exitCode, 0) << exporting.output;
  for (const char* writer : {"export obj ", "export vdb ", "export png ", "export cache "})
    EXPECT_TRUE(has(exporting.output, writer)) << writer << "\n" << exporting.output;
  EXPECT_TRUE(has(exporting.output, " threads=2 ")) << exporting.output;
  EXPECT_TRUE(fs::exists(out / "obj" / "default_0003.obj"));
  EXPECT_TRUE(fs::exists(out / "png" / "default_0003.png"));
}

TEST_F(FlagEffects, ExportWritesTheSameBytesOnOneThreadAndTwoAndQuietLeavesTheSummary) {
  const fs::path scene = writeScene("thrown.json", kThrownBall);
  const fs::path out = folder_ / "run";
  ASSERT_EQ(
      runSoftbake("run " + quoted(scene) + " --frames 6 --no-render -q -o " + quoted(out)).exitCode,
      0);
  std::map<std::string, std::string> byThreads[2];
  for (int threads = 1; threads <= 2; ++threads) {
    fs::remove_all(out / "obj");
    const Result exported = runSoftbake("export " + quoted(out) + " --obj --vdb -j " +
                                        std::to_string(threads) + (threads == 1 ? " -q" : ""));
    ASSERT_EQ(exported.exitCode, 0) << exported.output;
    byThreads[threads - 1] = filesUnder(out / "obj");
    // Progress lines go only to a run that is not quiet.
    EXPECT_EQ(has(exported.output, "frame 6/6"), threads == 2) << exported.output;
    EXPECT_TRUE(has(exported.output, "exported frames 1 to 6")) << exported.output;
  }
  EXPECT_EQ(byThreads[0].size(), 6u + 1);  // the frames and the .mtl
  EXPECT_TRUE(byThreads[0] == byThreads[1]);
}

TEST_F(FlagEffects, WedgeBakesTheSameVariantsOneAtATimeAsTwoAtOnce) {
  const fs::path scene = writeScene("thrown.json", kThrownBall);
  for (const char* parallel : {"1", "2"}) {
    const Result wedge = runSoftbake("wedge " + quoted(scene) + " --vary 'bodies[0].mass=0.5,2'" +
                                     " --parallel " + parallel + " --out " +
                                     quoted(folder_ / parallel) + " -- --frames 4 --no-render");
    ASSERT_EQ(wedge.exitCode, 0) << wedge.output;
  }
  for (const char* variant : {"wedge_000", "wedge_001"}) {
    auto one = filesUnder(folder_ / "1" / variant / "obj");
    EXPECT_EQ(one.size(), 4u + 1) << variant;
    EXPECT_TRUE(one == filesUnder(folder_ / "2" / variant / "obj")) << variant;
  }
}

TEST_F(FlagEffects, FarmCpusPerTaskReachesSbatchAndTheThreadsOfEveryJob) {
  const fs::path scene = writeScene("thrown.json", kThrownBall);
  const fs::path out = folder_ / "farm";
  const Result farm =
      runSoftbake("farm slurm " + quoted(scene) + " --out " + quoted(out) + " --cpus-per-task 3");
  ASSERT_EQ(farm.exitCode, 0) << farm.output;
  for (const char* script : {"simulate_thrown.sbatch", "export_thrown.sbatch"}) {
    const std::string text = readFile(out / "slurm" / script);
    EXPECT_TRUE(has(text, "#SBATCH --cpus-per-task=3\n")) << script << "\n" << text;
    EXPECT_TRUE(has(text, " -j 3")) << script << "\n" << text;
  }
}

}  // namespace
}  // namespace softbake::test
