#include "output/atomic_file.hpp"

#include <fcntl.h>
#include <limits.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <system_error>
#include <vector>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

// Distinguishes temporary names of concurrent writers in one process; the pid separates processes.
std::atomic<unsigned long> temporaryCounter{0};

// std::error_code's message() is strerror's text without strerror's shared static buffer, which
// several writer threads could otherwise overwrite under each other.
std::string systemReason(int error) {
  return std::error_code(error, std::generic_category()).message();
}

[[noreturn]] void fail(const std::filesystem::path& path, const char* step, int error) {
  throw OutputFailure(cat("cannot write '", path.string(), "': ", step, ": ", systemReason(error)));
}

std::filesystem::path temporaryPath(const std::filesystem::path& path) {
  const unsigned long n = temporaryCounter.fetch_add(1, std::memory_order_relaxed);
  return path.parent_path() / cat(".", path.filename().string(), ".tmp-", long(::getpid()), "-", n);
}

// Returns 0 or the errno of the first failing call. Loops because writev(2) may write less than
// asked (signals, large buffers) and takes at most IOV_MAX pieces per call.
int writeAll(int fd, std::span<const std::string_view> parts) {
  iovec pieces[64];
  std::size_t part = 0, offset = 0;  // the first byte not yet written
  while (part < parts.size()) {
    int count = 0;
    for (std::size_t i = part; i < parts.size() && count < std::min(64, IOV_MAX); ++i) {
      const std::size_t skip = i == part ? offset : 0;
      if (parts[i].size() == skip) continue;
      pieces[count++] = {const_cast<char*>(parts[i].data() + skip), parts[i].size() - skip};
    }
    if (count == 0) break;
    const ssize_t written = ::writev(fd, pieces, count);
    if (written < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    // Step over what the kernel took, which may end inside a part.
    std::size_t left = std::size_t(written);
    while (part < parts.size() && left >= parts[part].size() - offset) {
      left -= parts[part].size() - offset;
      ++part;
      offset = 0;
    }
    offset += left;
  }
  return 0;
}

/// The crash tests' hook: SOFTBAKE_TEST_KILL_BEFORE_RENAME=<file name> kills the process with
/// SIGKILL once that file's data is written under its temporary name and before the rename, the
/// worst moment for a kill, reached deterministically.
void killHereIfAsked(const std::filesystem::path& path) {
  static const char* const name = std::getenv("SOFTBAKE_TEST_KILL_BEFORE_RENAME");
  if (name && path.filename() == name) ::kill(::getpid(), SIGKILL);
}

}  // namespace

void writeFileAtomically(const std::filesystem::path& path, std::string_view data,
                         Durability durability) {
  writeFileAtomically(path, std::span<const std::string_view>(&data, 1), durability);
}

void writeFileAtomically(const std::filesystem::path& path, std::span<const std::string_view> parts,
                         Durability durability) {
  const std::filesystem::path temporary = temporaryPath(path);
  // O_EXCL: never write through a stale temporary that is a symlink planted by someone else.
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) fail(path, "cannot create a temporary file", errno);

  int error = writeAll(fd, parts);
  const char* step = "write failed";
  if (error == 0 && durability == Durability::PowerLoss && ::fsync(fd) != 0) {
    error = errno;
    step = "fsync failed";
  }
  // close() reports delayed write errors on network file systems, so its result counts too.
  if (::close(fd) != 0 && error == 0) {
    error = errno;
    step = "close failed";
  }
  if (error == 0) killHereIfAsked(path);
  if (error == 0 && ::rename(temporary.c_str(), path.c_str()) != 0) {
    error = errno;
    step = "rename failed";
  }
  if (error != 0) {
    ::unlink(temporary.c_str());
    fail(path, step, error);
  }
  if (durability == Durability::PowerLoss) {
    // The rename lives in the directory: without this a power cut can bring the old name back.
    const std::filesystem::path directory =
        path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    const int directoryFd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (directoryFd < 0) fail(path, "cannot open its directory to fsync it", errno);
    const int synced = ::fsync(directoryFd);
    const int syncError = errno;
    ::close(directoryFd);
    if (synced != 0) fail(path, "fsync of its directory failed", syncError);
  }
}

void makeDirectories(const std::filesystem::path& directory) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error)
    throw OutputFailure(
        cat("cannot create output directory '", directory.string(), "': ", error.message()));
  if (!std::filesystem::is_directory(directory, error))
    throw OutputFailure(cat("cannot create output directory '", directory.string(),
                            "': a file of that name is in the way"));
}

}  // namespace softbake
