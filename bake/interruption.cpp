#include "bake/interruption.hpp"

namespace softbake {

namespace {

volatile std::sig_atomic_t requestedStop = 0;

extern "C" void requestStop(int signal) {
  requestedStop = signal;
}

}  // namespace

InterruptionGuard::InterruptionGuard() {
  requestedStop = 0;
  struct sigaction action {};
  action.sa_handler = requestStop;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: the handler runs once; a second Ctrl-C gets the default action and ends the
  // process, for a user who does not want to wait for the frame in progress.
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, &previousInterrupt_);
  sigaction(SIGTERM, &action, &previousTerminate_);
}

InterruptionGuard::~InterruptionGuard() {
  sigaction(SIGINT, &previousInterrupt_, nullptr);
  sigaction(SIGTERM, &previousTerminate_, nullptr);
}

int InterruptionGuard::signal() const {
  return requestedStop;
}

const char* signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

}  // namespace softbake
