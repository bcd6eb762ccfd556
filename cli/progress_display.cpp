#include "cli/progress_display.hpp"

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
  const double elapsed = elapsedSeconds();
  const double fps = elapsed > 0 ? frame / elapsed : 0;
  const double eta = fps > 0 ? (total_ - frame) / fps : 0;
  if (terminal_) {
    const auto now = std::chrono::steady_clock::now();
    // Redrawing more than ~20 times a second only costs time.
    if (frame != total_ && now - lastDraw_ < std::chrono::milliseconds(50)) return;
    lastDraw_ = now;
    constexpr int kWidth = 30;
    const int filled = total_ > 0 ? frame * kWidth / total_ : kWidth;
    std::string bar(std::size_t(filled), '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r[%s] frame %d/%d  %.1f frames/s  ETA %.1f s   ", bar.c_str(), frame,
                 total_, fps, eta);
    std::fflush(stderr);
    return;
  }
  const int tenth = total_ > 0 ? frame * 10 / total_ : 10;
  if (tenth == lastPlainTenth_) return;
  lastPlainTenth_ = tenth;
  std::fprintf(stderr, "frame %d/%d  %.1f frames/s  ETA %.1f s\n", frame, total_, fps, eta);
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
