// What the progress display writes to stderr: a line every tenth of the run for a log, a redrawn
// bar on a terminal (a pseudo-terminal here), and nothing when quiet.
#include "bake/progress_display.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace softbake {
namespace {

/// Sends stderr to `fd` while it lives; the display looks at what stderr is when it is made.
class StderrTo {
 public:
  explicit StderrTo(int fd) : saved_(::dup(STDERR_FILENO)) {
    std::fflush(stderr);
    ::dup2(fd, STDERR_FILENO);
  }
  ~StderrTo() {
    std::fflush(stderr);
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
  }
  StderrTo(const StderrTo&) = delete;
  StderrTo& operator=(const StderrTo&) = delete;

 private:
  int saved_;
};

/// Everything that can be read from `fd` now, without waiting for more.
std::string drain(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  std::string text;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) text.append(buffer, std::size_t(n));
  return text;
}

/// A log: stderr into a pipe. Returns what the display wrote for frames 1..`total`.
std::string plainOutput(int total, bool quiet) {
  int ends[2];
  if (::pipe(ends) != 0) return "(no pipe)";
  {
    StderrTo redirect(ends[1]);
    ProgressDisplay progress(total, quiet);
    for (int frame = 1; frame <= total; ++frame) progress.update(frame);
    progress.finish();
  }
  ::close(ends[1]);
  const std::string text = drain(ends[0]);
  ::close(ends[0]);
  return text;
}

/// The frame numbers of the plain lines, each checked for its form: the first has no rate yet
/// (nothing was simulated to measure one), every later line has one.
std::vector<int> plainLineFrames(const std::string& text, int total) {
  const std::regex first("frame ([0-9]+)/" + std::to_string(total));
  const std::regex line("frame ([0-9]+)/" + std::to_string(total) +
                        "  [0-9]+\\.[0-9] frames/s  ETA [0-9]+\\.[0-9] s");
  std::vector<int> frames;
  std::size_t begin = 0;
  for (std::size_t end; (end = text.find('\n', begin)) != std::string::npos; begin = end + 1) {
    std::smatch match;
    const std::string one = text.substr(begin, end - begin);
    EXPECT_TRUE(std::regex_match(one, match, begin == 0 ? first : line)) << one;
    if (!match.empty()) frames.push_back(std::stoi(match[1]));
  }
  EXPECT_EQ(begin, text.size()) << "a partial last line: " << text;
  return frames;
}

TEST(ProgressDisplay, ALogGetsOneLinePerTenthOfTheRun) {
  EXPECT_EQ(plainLineFrames(plainOutput(100, false), 100),
            (std::vector<int>{1, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100}));
  // 20 frames: every second frame starts a new tenth.
  EXPECT_EQ(plainLineFrames(plainOutput(20, false), 20),
            (std::vector<int>{1, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20}));
  // Fewer frames than tenths: every frame gets its line.
  EXPECT_EQ(plainLineFrames(plainOutput(3, false), 3), (std::vector<int>{1, 2, 3}));
  // The last line has nothing left to wait for.
  const std::string text = plainOutput(20, false);
  EXPECT_NE(text.find("frame 20/20  "), std::string::npos) << text;
  EXPECT_TRUE(text.ends_with(" frames/s  ETA 0.0 s\n")) << text;
}

TEST(ProgressDisplay, QuietWritesNothing) {
  EXPECT_EQ(plainOutput(20, true), "");
}

/// A terminal: stderr on a raw pseudo-terminal, so what arrives is what was written.
class Terminal : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(::openpty(&master_, &slave_, nullptr, nullptr, nullptr), 0);
    termios raw{};
    ASSERT_EQ(::tcgetattr(slave_, &raw), 0);
    ::cfmakeraw(&raw);
    ASSERT_EQ(::tcsetattr(slave_, TCSANOW, &raw), 0);
  }
  void TearDown() override {
    ::close(slave_);
    ::close(master_);
  }
  int master_ = -1, slave_ = -1;
};

TEST_F(Terminal, ABarIsRedrawnInPlaceAndEndsItsLine) {
  {
    StderrTo redirect(slave_);
    ProgressDisplay progress(20, false);
    progress.update(1);
    // Redraws come at most every 50 ms; after a longer pause the next update draws.
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    progress.update(10);
    for (int frame = 11; frame <= 20; ++frame) progress.update(frame);
    progress.finish();
  }
  const std::string text = drain(master_);
  const std::string half = "\r[" + std::string(15, '#') + std::string(15, '.') + "] frame 10/20  ";
  const std::string full = "\r[" + std::string(30, '#') + "] frame 20/20  ";
  EXPECT_NE(text.find(half), std::string::npos) << text;
  const std::size_t last = text.find(full);
  ASSERT_NE(last, std::string::npos) << "the last frame is always drawn: " << text;
  EXPECT_NE(text.find("ETA 0.0 s", last), std::string::npos) << text;
  // One line in all, ended by finish(); no log lines on a terminal.
  EXPECT_EQ(text.find('\n'), text.size() - 1) << text;
  EXPECT_EQ(text.find("\nframe"), std::string::npos) << text;
}

TEST_F(Terminal, QuietDrawsNoBar) {
  {
    StderrTo redirect(slave_);
    ProgressDisplay progress(20, true);
    for (int frame = 1; frame <= 20; ++frame) progress.update(frame);
    progress.finish();
  }
  EXPECT_EQ(drain(master_), "");
}

TEST(FormatBytes, PicksTheUnit) {
  EXPECT_EQ(formatBytes(999), "999 B");
  EXPECT_EQ(formatBytes(1000), "1 kB");
  EXPECT_EQ(formatBytes(980400), "980 kB");
  EXPECT_EQ(formatBytes(12400000), "12.4 MB");
}

}  // namespace
}  // namespace softbake
