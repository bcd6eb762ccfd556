#pragma once
/// Progress of a run on stderr: a live bar on a terminal, a plain line every tenth of the run
/// otherwise (logs and CI stay readable).

#include <chrono>
#include <cstdint>
#include <string>

namespace softbake {

class ProgressDisplay {
 public:
  ProgressDisplay(int totalFrames, bool quiet);
  /// Frame `frame` of the total has been simulated.
  void update(int frame);
  /// Ends the live line, if any.
  void finish();
  double elapsedSeconds() const;

 private:
  int total_;
  bool quiet_;
  bool terminal_;
  int lastPlainTenth_ = -1;
  /// The first frame reported and when: rates count the frames after it, so a frame that needed no
  /// simulation (frame 1, the initial state; the frames a resumed run skips) does not inflate them.
  int firstFrame_ = -1;
  std::chrono::steady_clock::time_point firstTime_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point lastDraw_;
};

/// "12.4 MB", "980 kB".
std::string formatBytes(std::uint64_t bytes);

}  // namespace softbake
