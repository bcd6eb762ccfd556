// Bad input through the real `softbake` binary, in a child process as a user would meet it: the
// documented exit status (1), a message naming the file, and no frames on disk.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "softbake_process.hpp"
#include "tests/support/scoped_environment.hpp"

namespace fs = std::filesystem;

namespace {

using softbake::test::quoted;
using softbake::test::Result;
using softbake::test::runSoftbake;

fs::path importData(const std::string& name) {
  return fs::path(SOFTBAKE_SOURCE_DIR) / "tests" / "data" / "import" / name;
}

// Every file under `folder`, which need not exist.
std::size_t filesUnder(const fs::path& folder) {
  std::size_t files = 0;
  std::error_code error;
  if (!fs::exists(folder, error)) return 0;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder))
    files += entry.is_regular_file() ? 1 : 0;
  return files;
}

using TestImports = softbake::test::ScopedEnvironment;

class ImportCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = fs::temp_directory_path() /
              (std::string("softbake_import_cli_") + info->name() + "_" + std::to_string(getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  fs::path folder_;
};

TEST_F(ImportCliTest, AGltfThatLostAFaceIsRefusedWithExitOneNamingTheFileAndNoFrames) {
  const fs::path bad = importData("box_out_of_range_index.gltf");
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run " + quoted(bad.string()) + " --frames 3 --no-render -o " +
                                 quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("softbake: error: " + bad.string() +
                            ": the import lost geometry: faces dropped"),
            std::string::npos)
      << run.output;
  EXPECT_EQ(filesUnder(out), 0u) << "frames written for a refused file";
}

TEST_F(ImportCliTest, AcceptingTheLossRunsWithAWarningNamingTheFile) {
  const fs::path bad = importData("box_out_of_range_index.gltf");
  const fs::path out = folder_ / "out";
  const Result run =
      runSoftbake("run " + quoted(bad.string()) +
                  " --accept-lossy-import --frames 3 --no-render -q -o " + quoted(out.string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(
      run.output.find("warning: " + bad.string() + ": the import lost geometry: faces dropped"),
      std::string::npos)
      << run.output;
  EXPECT_TRUE(fs::exists(out / "obj" / "box_out_of_range_index_0003.obj"));
}

TEST_F(ImportCliTest, BenchRefusesTheLossTooUnlessAccepted) {
  const std::string bad = quoted(importData("box_out_of_range_index.gltf").string());
  const Result refused = runSoftbake("bench " + bad + " --frames 2");
  EXPECT_EQ(refused.exitCode, 1) << refused.output;
  EXPECT_NE(refused.output.find("faces dropped"), std::string::npos) << refused.output;
  const Result accepted = runSoftbake("bench " + bad + " --frames 2 --accept-lossy-import");
  EXPECT_EQ(accepted.exitCode, 0) << accepted.output;
}

TEST_F(ImportCliTest, AFileAboveTheFaceCapIsRefusedNamingTheFileAndTheFlag) {
  const fs::path box = importData("box.gltf");
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run " + quoted(box.string()) + " --max-faces 11 --no-render -o " +
                                 quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find(box.string() + ": 12 faces, above the limit of 11 per file "
                                           "(--max-faces"),
            std::string::npos)
      << run.output;
  EXPECT_EQ(filesUnder(out), 0u);
}

TEST_F(ImportCliTest, ARunWhoseFramesWouldNotFitTheOutputBoundIsRefusedBeforeAnyWork) {
  const fs::path out = folder_ / "out";
  // The box's OBJ frames are about a kilobyte each: a million of them are about a gigabyte.
  const Result run =
      runSoftbake("run " + quoted(importData("box.gltf").string()) +
                  " --frames 1000000 --max-output-gib 0.5 --no-render -o " + quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("softbake: error: scene 'box': 1000000 frames of about "),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("above the limit of 512.0 MiB (--max-output-gib raises it)"),
            std::string::npos)
      << run.output;
  EXPECT_EQ(run.output.find("substeps:"), std::string::npos) << "work started:\n" << run.output;
  EXPECT_EQ(filesUnder(out), 0u);
}

TEST_F(ImportCliTest, TooManyBodiesAreRefusedForBuiltInScenesToo) {
  const Result run = runSoftbake("bench balls1k --frames 2 --max-bodies 3");
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("scene 'balls1k': 4 bodies, above the limit of 3 (--max-bodies"),
            std::string::npos)
      << run.output;
}

// The limit kills the process that reads the file, never softbake itself: it ends with 1 exactly
// (a signal that reached it would fail the test in runSoftbake()).
TEST_F(ImportCliTest, AnImportPastItsTimeLimitExitsWithOneNamingTheLimitAndWritesNothing) {
  const fs::path box = importData("box.gltf");
  const fs::path out = folder_ / "out";
  const TestImports stalled("SOFTBAKE_TEST_IMPORT_STALL_SECONDS", "60");
  const Result run =
      runSoftbake("run " + quoted(box.string()) +
                  " --max-import-seconds 1 --frames 2 --no-render -j 1 -o " + quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("softbake: error: " + box.string() +
                            ": reading the file took longer than the import time limit of 1 s "
                            "(--max-import-seconds or settings.import.max_seconds raises it)"),
            std::string::npos)
      << run.output;
  EXPECT_EQ(filesUnder(out), 0u) << "files written for a refused file";
}

TEST_F(ImportCliTest, AnImportOverItsMemoryLimitExitsWithOneNamingTheLimitAndWritesNothing) {
  const fs::path box = importData("box.gltf");
  const fs::path out = folder_ / "out";
  const TestImports allocating("SOFTBAKE_TEST_IMPORT_ALLOCATE_MIB", "1024");
  const Result run = runSoftbake("run " + quoted(box.string()) +
                                 " --max-import-memory 256 --frames 2 --no-render -j 1 -o " +
                                 quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("softbake: error: " + box.string() +
                            ": reading the file took more memory than the import memory limit of "
                            "256.0 MiB (--max-import-memory or settings.import.max_memory_mib "
                            "raises it)"),
            std::string::npos)
      << run.output;
  EXPECT_EQ(filesUnder(out), 0u) << "files written for a refused file";
}

// assimp 5.2.5's IQM reader reads this file's mesh from past the file's end, and what it finds
// there decides what it does (tests/data/meshes/README.md): in a release build it asks for
// 17.3 GiB at once and, given them, fills them until the machine has no memory left; under
// AddressSanitizer it finds no vertices; it may crash. Whichever, the run ends at once with exit 1
// and an error naming the file.
TEST_F(ImportCliTest, AssimpsRunawayIqmReaderEndsTheRunWithOneAndWritesNothing) {
  const fs::path iqm = fs::path(SOFTBAKE_SOURCE_DIR) / "tests" / "data" / "meshes" / "broken" /
                       "InvalidMeshOffset.iqm";
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run " + quoted(iqm.string()) +
                                 " --max-import-memory 1024 --frames 2 --no-render -j 1 -o " +
                                 quoted(out.string()));
  EXPECT_EQ(run.exitCode, 1) << run.output;
  EXPECT_NE(run.output.find("softbake: error: " + iqm.string() + ": "), std::string::npos)
      << run.output;
  EXPECT_EQ(filesUnder(out), 0u) << "files written for a refused file";
}

}  // namespace
