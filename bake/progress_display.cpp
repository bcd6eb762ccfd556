#include "bake/progress_display.hpp"

#include <unistd.h>

#include <cstdio>

namespace softbake {

ProgressDisplay::ProgressDisplay(int totalFrames, bool quiet)
    : total_(totalFrames),
      quiet_(quiet),
      terminal_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      lastDraw_(start_) {}

double ProgressDisplay::elapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressDisplay::update(int frame) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (firstFrame_ < 0) {
    firstFrame_ = frame;
    firstTime_ = now;
  }
  const double elapsed = std::chrono::duration<double>(now - firstTime_).count();
  const bool measured = frame > firstFrame_;
  const double fps = measured && elapsed > 0 ? (frame - firstFrame_) / elapsed : 0;
  const double eta = fps > 0 ? (total_ - frame) / fps : 0;
  // No rate before a frame has been simulated: there is nothing to measure yet.
  char rate[64] = "";
  if (measured || frame == total_)
    std::snprintf(rate, sizeof rate, "  %.1f frames/s  ETA %.1f s", fps, eta);
  if (terminal_) {
    // Redrawing more than ~20 times a second only costs time.
    if (frame != total_ && now - lastDraw_ < std::chrono::milliseconds(50)) return;
    lastDraw_ = now;
    constexpr int kWidth = 30;
    const int filled = total_ > 0 ? frame * kWidth / total_ : kWidth;
    std::string bar(std::size_t(filled), '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r[%s] frame %d/%d%s   ", bar.c_str(), frame, total_, rate);
    std::fflush(stderr);
    return;
  }
  const int tenth = total_ > 0 ? frame * 10 / total_ : 10;
  if (tenth == lastPlainTenth_) return;
  lastPlainTenth_ = tenth;
  std::fprintf(stderr, "frame %d/%d%s\n", frame, total_, rate);
}

void ProgressDisplay::finish() {
  if (!quiet_ && terminal_) std::fprintf(stderr, "\n");
}

std::string formatBytes(std::uint64_t bytes) {
  char text[32];
  if (bytes >= 1000000)
    std::snprintf(text, sizeof text, "%.1f MB", double(bytes) / 1e6);
  else if (bytes >= 1000)
    std::snprintf(text, sizeof text, "%.0f kB", double(bytes) / 1e3);
  else
    std::snprintf(text, sizeof text, "%llu B", static_cast<unsigned long long>(bytes));
  return text;
}

}  // namespace softbake
