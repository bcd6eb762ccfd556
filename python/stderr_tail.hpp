#pragma once
/// What `softbake.run()` needs to raise the error the command prints. runBake() reports a
/// failure the way the command does, on stderr ("\nsoftbake: error: MESSAGE\n", exit code 1), and
/// does not throw; while a StderrTail lives, file descriptor 2 goes through a pipe whose reader
/// passes everything on to where stderr went before, so the user still sees it, and keeps the end.

#include <cstddef>
#include <string>
#include <thread>

namespace softbake::python {

class StderrTail {
 public:
  /// Redirects file descriptor 2; when that fails, captures nothing and changes nothing.
  explicit StderrTail(std::size_t keep = 1 << 16);
  ~StderrTail();
  StderrTail(const StderrTail&) = delete;
  StderrTail& operator=(const StderrTail&) = delete;

  /// Puts file descriptor 2 back and returns the last `keep` bytes written to it.
  std::string finish();

 private:
  std::size_t keep_;
  int saved_ = -1;    ///< where stderr went before
  int readEnd_ = -1;  ///< the pipe's end the reader drains
  std::string tail_;
  std::thread reader_;
};

/// The message of the last "softbake: error: MESSAGE" report in `text`, or "" when there is none.
std::string reportedError(const std::string& text);

}  // namespace softbake::python
