#pragma once
/// Wall time of each stage of a substep, for `softbake bench`. Off (a null StageTimes) it costs a
/// branch per stage; on, one steady_clock read per stage. The simulation itself never reads it.

#include <array>
#include <chrono>
#include <cstdint>

namespace softbake {

/// The stages of Simulator::step, in order. BroadPhase is the broad phase's whole findPairs: for
/// sbhash the surface subdivision, leaf boxes and box hash; for bvh the refit and the traversal.
enum class Stage : int {
  Forces,
  Integration,
  Boxes,
  BroadPhase,
  NarrowPhase,
  Response,
  Planes,
  Failsafe,
  Contacts
};
inline constexpr int kStageCount = 9;

/// "forces", "integration", "boxes", "broad_phase", "narrow_phase", "response", "planes",
/// "failsafe", "contacts" (those the implicit solve keeps apart, found before it).
const char* stageName(Stage stage);

struct StageTimes {
  std::array<std::int64_t, kStageCount> nanoseconds{};
  std::int64_t total() const {
    std::int64_t sum = 0;
    for (std::int64_t t : nanoseconds) sum += t;
    return sum;
  }
};

/// Each lap(stage) charges the time since the previous lap (or the clock's start) to `stage`.
class StageClock {
 public:
  /// Null `times`: every lap does nothing. Otherwise `*times` is cleared.
  explicit StageClock(StageTimes* times) : times_(times) {
    if (times_) {
      *times_ = {};
      last_ = std::chrono::steady_clock::now();
    }
  }
  void lap(Stage stage) {
    if (!times_) return;
    const auto now = std::chrono::steady_clock::now();
    times_->nanoseconds[int(stage)] += (now - last_).count();
    last_ = now;
  }

 private:
  StageTimes* times_;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace softbake
