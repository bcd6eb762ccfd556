#pragma once
/// Runs the real `softbake` binary in a child process, as a user or a pipeline would, for the CLI
/// tests: its exit code and everything it printed.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/support/scratch_directory.hpp"  // readFile

namespace softbake::test {

struct Result {
  int exitCode = -1;  ///< -1: killed by a signal (which fails the test) or never started
  int signal = 0;     ///< the signal that killed it, if one did
  std::string output;
};

/// `text` as one shell word.
inline std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

inline std::string quoted(const std::filesystem::path& path) {
  return quoted(path.string());
}

/// A shell command's exit code and its stdout (what the command line sends there). `command` is
/// one simple command (words and redirections, no `;`, `|` or `&&`): the shell execs it, so
/// that a death by a signal reaches here as one. Run by the shell as a child, it would come back
/// as the exit code 128 + the signal, a code softbake uses itself (130, 143) and that a test
/// asserting only a non-zero code would take for a refusal. A death by a signal fails the test.
inline Result runShell(const std::string& command) {
  Result result;
  FILE* pipe = popen(("exec " + command).c_str(), "r");
  if (!pipe) {
    ADD_FAILURE() << "cannot start: " << command;
    return result;
  }
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
    result.output.append(buffer, read);
  const int status = pclose(pipe);
  if (WIFEXITED(status)) {
    result.exitCode = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.signal = WTERMSIG(status);
    ADD_FAILURE() << "killed by signal " << result.signal << " (" << strsignal(result.signal)
                  << "): " << command << "\n"
                  << result.output;
  }
  return result;
}

/// `softbake ARGUMENTS`, stdout and stderr together; with `stderrToo` false stderr is dropped,
/// so the output is exactly what a pipe would read.
inline Result runSoftbake(const std::string& arguments, bool stderrToo = true) {
  return runShell(std::string(SOFTBAKE_BINARY) + " " + arguments +
                  (stderrToo ? " 2>&1" : " 2>/dev/null"));
}

/// A fresh folder per test under the system temp folder, removed afterwards.
class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    // The process id keeps runs of the suite from other checkouts out of each other's way.
    std::string name = std::string("softbake_cli_") + info->test_suite_name() + "_" + info->name() +
                       "_" + std::to_string(::getpid());
    for (char& c : name)
      if (c == '/') c = '_';  // parameterised tests
    folder_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }

  std::filesystem::path writeScene(const std::string& name, const std::string& text) {
    const std::filesystem::path path = folder_ / name;
    std::ofstream(path) << text;
    return path;
  }

  std::filesystem::path folder_;
};

}  // namespace softbake::test
