#pragma once
/// SIGINT and SIGTERM during a bake. The first one asks the run to stop after the frame in
/// progress, so it can write what it has and a manifest that `--resume` continues from; a second
/// one ends the process at once, as if nothing were installed.

#include <csignal>

namespace softbake {

/// The status a run interrupted by `signal` exits with: 128 + the signal, as shells report it
/// (130 for SIGINT, 143 for SIGTERM).
constexpr int interruptedExitCode(int signal) {
  return 128 + signal;
}

class InterruptionGuard {
 public:
  /// Installs the handlers; the destructor puts the previous ones back.
  InterruptionGuard();
  ~InterruptionGuard();
  InterruptionGuard(const InterruptionGuard&) = delete;
  InterruptionGuard& operator=(const InterruptionGuard&) = delete;

  /// The signal that asked the run to stop, or 0.
  int signal() const;

 private:
  struct sigaction previousInterrupt_ {};
  struct sigaction previousTerminate_ {};
};

/// "SIGINT", "SIGTERM".
const char* signalName(int signal);

}  // namespace softbake
