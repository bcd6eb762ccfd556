// The exit-status contract of docs/commands.md and --help, class by class, through the binary:
// 0 done, 1 bad input (flags as well as files), 2 the simulation failed, 3 an output could not be
// written, 143 SIGTERM (tested with --resume in resume_test.cpp).
#include <gtest/gtest.h>

#include "tests/cli/softbake_process.hpp"

namespace softbake::test {
namespace {

class ExitStatus : public CliTest {};

TEST_F(ExitStatus, DoneIsZero) {
  EXPECT_EQ(runSoftbake("--help").exitCode, 0);
  EXPECT_EQ(runSoftbake("--version").exitCode, 0);
  EXPECT_EQ(runSoftbake("run --frames 2 --no-render -q -o " + quoted(folder_ / "ok")).exitCode, 0);
}

TEST_F(ExitStatus, EveryKindOfBadInputIsOne) {
  // CLI11 would exit 105, 106, 108 or 109 for these.
  for (const char* arguments : {"run --frames 0", "run --fps 0", "run --substeps 0",
                                "run --levels 9", "run --render --no-render", "run --no-such-flag",
                                "rnu", "", "run no_such_scene.json", "export", "verify"}) {
    const Result result = runSoftbake(arguments);
    EXPECT_EQ(result.exitCode, 1) << arguments << "\n" << result.output;
  }
}

TEST_F(ExitStatus, APinPastTheMeshFileIsOneNamingTheSceneTheKeyTheFileAndItsCount) {
  // One triangle; its `v` statements are the file's vertices 0 to 2.
  std::ofstream(folder_ / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n";
  const std::filesystem::path scene =
      writeScene("scene.json", R"({"bodies": [{"mesh": "tri.obj", "pins": {"indices": [2, 3]}}]})");
  const Result result =
      runSoftbake("run " + quoted(scene) + " --frames 2 --no-render -o " + quoted(folder_ / "out"));
  EXPECT_EQ(result.exitCode, 1) << result.output;
  EXPECT_NE(result.output.find(scene.string() +
                               ": bodies[0].pins.indices[1]: vertex 3 is beyond the 3 vertices "
                               "of tri.obj (indices count from 0)"),
            std::string::npos)
      << result.output;
  EXPECT_FALSE(std::filesystem::exists(folder_ / "out"));
}

TEST_F(ExitStatus, AMisspeltCommandIsNamedWithTheNearestOne) {
  const Result result = runSoftbake("rnu");
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.output.find("no command 'rnu'; did you mean 'run'?"), std::string::npos)
      << result.output;
  EXPECT_NE(runSoftbake("expotr x").output.find("did you mean 'export'?"), std::string::npos);
}

TEST_F(ExitStatus, ASimulationThatBlowsUpIsTwo) {
  const Result result = runSoftbake("run --integrator explicit --substeps 1 --frames 24 -q -o " +
                                    quoted(folder_ / "blown"));
  EXPECT_EQ(result.exitCode, 2) << result.output;
  EXPECT_NE(result.output.find("blew up"), std::string::npos) << result.output;
}

TEST_F(ExitStatus, AnOutputThatCannotBeWrittenIsThree) {
  // A file where the output folder should be.
  std::ofstream(folder_ / "taken") << "not a folder";
  const Result taken = runSoftbake("run --frames 2 --no-render -q -o " + quoted(folder_ / "taken"));
  EXPECT_EQ(taken.exitCode, 3) << taken.output;
  EXPECT_NE(taken.output.find("taken"), std::string::npos) << taken.output;
  // A file-size limit, as a full disk.
  const std::string command =
      "sh -c " +
      quoted("ulimit -f 8; exec " + std::string(SOFTBAKE_BINARY) +
             " run --frames 3 --no-render -q -o " + (folder_ / "full").string()) +
      " >/dev/null 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
}

}  // namespace
}  // namespace softbake::test
