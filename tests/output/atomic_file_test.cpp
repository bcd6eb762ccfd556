#include "output/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include "core/error.hpp"
#include "tests/support/scratch_directory.hpp"

namespace softbake {
namespace {

using test::listDirectory;
using test::readFile;
using test::ScratchDirectory;

TEST(AtomicFile, WritesAndReplacesWholeFiles) {
  ScratchDirectory dir;
  const auto path = dir.path() / "frame.obj";
  writeFileAtomically(path, "first version\n");
  EXPECT_EQ(readFile(path), "first version\n");
  writeFileAtomically(path, "second\n");
  EXPECT_EQ(readFile(path), "second\n");
  writeFileAtomically(path, "");
  EXPECT_EQ(readFile(path), "");
  EXPECT_EQ(listDirectory(dir.path()), std::vector<std::string>{"frame.obj"});
}

TEST(AtomicFile, WritesManyPartsInOrder) {
  ScratchDirectory dir;
  // More parts than one writev(2) call takes, empty ones among them.
  std::vector<std::string> texts;
  for (int i = 0; i < 300; ++i) texts.push_back(i % 7 == 0 ? "" : std::to_string(i) + ",");
  const std::vector<std::string_view> parts(texts.begin(), texts.end());
  std::string expected;
  for (const std::string& text : texts) expected += text;
  writeFileAtomically(dir.path() / "parts.txt", parts);
  EXPECT_EQ(readFile(dir.path() / "parts.txt"), expected);
}

TEST(AtomicFile, FailedRenameRemovesTheTemporaryAndNamesThePath) {
  ScratchDirectory dir;
  // A directory where the file should go: open and write succeed, rename(2) fails.
  const auto path = dir.path() / "frame.obj";
  std::filesystem::create_directory(path);
  try {
    writeFileAtomically(path, "data");
    FAIL() << "expected softbake::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Is a directory"), std::string::npos) << e.what();
  }
  EXPECT_EQ(listDirectory(dir.path()), std::vector<std::string>{"frame.obj"});
}

TEST(AtomicFile, WriteFailingMidwayLeavesNoFile) {
  ScratchDirectory dir;
  const auto path = dir.path() / "big.obj";
  // A file-size limit makes write(2) fail with EFBIG after the first 4 KiB: a disk filling up,
  // reproducible even as root (where read-only directories do not stop writes).
  struct sigaction ignore = {}, previous = {};
  ignore.sa_handler = SIG_IGN;
  ASSERT_EQ(::sigaction(SIGXFSZ, &ignore, &previous), 0);
  rlimit saved{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  rlimit small = saved;
  small.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string error;
  try {
    writeFileAtomically(path, std::string(1 << 20, 'x'));
  } catch (const Error& e) {
    error = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &saved);
  ::sigaction(SIGXFSZ, &previous, nullptr);

  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  EXPECT_NE(error.find("write failed"), std::string::npos) << error;
  EXPECT_TRUE(listDirectory(dir.path()).empty());
}

TEST(AtomicFile, ReadOnlyDirectoryIsAClearError) {
  namespace fs = std::filesystem;
  ScratchDirectory dir;
  const auto readOnly = dir.path() / "locked", writable = dir.path() / "open";
  fs::create_directory(readOnly);
  fs::create_directory(writable);
  fs::permissions(dir.path(), fs::perms::owner_all | fs::perms::others_exec);
  fs::permissions(writable, fs::perms::all);
  fs::permissions(readOnly, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::others_read |
                                fs::perms::others_exec);
  // Root writes into read-only folders, so the writes run in a child that, when root, becomes
  // nobody first. It writes into the open folder too: the locked one must fail for its
  // permissions, not because the child can reach nothing. The child sends back what happened.
  int pipeEnds[2];
  ASSERT_EQ(::pipe(pipeEnds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(pipeEnds[0]);
    std::string message = "(no error)";
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) {
      message = "(could not become nobody)";
    } else {
      try {
        writeFileAtomically(writable / "frame.obj", "data");
        writeFileAtomically(readOnly / "frame.obj", "data");
      } catch (const Error& e) {
        message = e.what();
      }
    }
    const ssize_t written = ::write(pipeEnds[1], message.data(), message.size());
    ::_exit(written == ssize_t(message.size()) ? 0 : 1);
  }
  ::close(pipeEnds[1]);
  std::string message;
  char buffer[512];
  for (ssize_t n; (n = ::read(pipeEnds[0], buffer, sizeof buffer)) > 0;)
    message.append(buffer, std::size_t(n));
  ::close(pipeEnds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << message;

  EXPECT_EQ(readFile(writable / "frame.obj"), "data");
  EXPECT_NE(message.find("'" + (readOnly / "frame.obj").string() + "'"), std::string::npos)
      << message;
  EXPECT_NE(message.find("Permission denied"), std::string::npos) << message;
  fs::permissions(readOnly, fs::perms::owner_all);
  EXPECT_TRUE(listDirectory(readOnly).empty());
}

TEST(AtomicFile, MissingDirectoryIsAnError) {
  ScratchDirectory dir;
  EXPECT_THROW(writeFileAtomically(dir.path() / "missing" / "frame.obj", "data"), Error);
}

TEST(MakeDirectories, CreatesParentsAndAcceptsExistingDirectories) {
  ScratchDirectory dir;
  const auto nested = dir.path() / "out" / "obj";
  makeDirectories(nested);
  makeDirectories(nested);
  EXPECT_TRUE(std::filesystem::is_directory(nested));
}

TEST(MakeDirectories, FileInTheWayIsAnErrorNamingTheDirectory) {
  ScratchDirectory dir;
  writeFileAtomically(dir.path() / "out", "not a directory");
  try {
    makeDirectories(dir.path() / "out" / "obj");
    FAIL() << "expected softbake::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot create output directory"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find((dir.path() / "out" / "obj").string()), std::string::npos);
  }
  EXPECT_THROW(makeDirectories(dir.path() / "out"), Error);
}

}  // namespace
}  // namespace softbake
