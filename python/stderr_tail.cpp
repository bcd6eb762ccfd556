#include "stderr_tail.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>

namespace softbake::python {

namespace {

/// Writes all of `size` bytes, or as many as `fd` takes.
void writeAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return;  // stderr is gone: the copy is all that is left
    data += written;
    size -= std::size_t(written);
  }
}

}  // namespace

StderrTail::StderrTail(std::size_t keep) : keep_(keep) {
  std::fflush(stderr);
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return;
  saved_ = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
  if (saved_ < 0 || ::dup2(ends[1], STDERR_FILENO) < 0) {
    if (saved_ >= 0) ::close(saved_);
    saved_ = -1;
    ::close(ends[0]);
    ::close(ends[1]);
    return;
  }
  ::close(ends[1]);  // file descriptor 2 is now the only writing end
  readEnd_ = ends[0];
  reader_ = std::thread([this] {
    char buffer[4096];
    for (;;) {
      const ssize_t got = ::read(readEnd_, buffer, sizeof buffer);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) break;  // end of file: file descriptor 2 was put back
      writeAll(saved_, buffer, std::size_t(got));
      tail_.append(buffer, std::size_t(got));
      if (tail_.size() > 2 * keep_) tail_.erase(0, tail_.size() - keep_);
    }
  });
}

StderrTail::~StderrTail() {
  finish();
}

std::string StderrTail::finish() {
  if (saved_ < 0) return std::move(tail_);
  std::fflush(stderr);
  ::dup2(saved_, STDERR_FILENO);  // closes the pipe's writing end: the reader sees end of file
  reader_.join();
  ::close(readEnd_);
  ::close(saved_);
  saved_ = readEnd_ = -1;
  if (tail_.size() > keep_) tail_.erase(0, tail_.size() - keep_);
  return std::move(tail_);
}

std::string reportedError(const std::string& text) {
  static const std::string kMarker = "softbake: error: ";
  std::size_t at = text.rfind("\n" + kMarker);
  if (at != std::string::npos)
    ++at;
  else if (text.compare(0, kMarker.size(), kMarker) == 0)
    at = 0;
  else
    return "";
  std::string message = text.substr(at + kMarker.size());
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
  return message;
}

}  // namespace softbake::python
