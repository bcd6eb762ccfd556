#include "core/stage_timer.hpp"

namespace softbake {

const char* stageName(Stage stage) {
  switch (stage) {
    case Stage::Contacts:
      return "contacts";
    case Stage::Forces:
      return "forces";
    case Stage::Integration:
      return "integration";
    case Stage::Boxes:
      return "boxes";
    case Stage::BroadPhase:
      return "broad_phase";
    case Stage::NarrowPhase:
      return "narrow_phase";
    case Stage::Response:
      return "response";
    case Stage::Planes:
      return "planes";
    case Stage::Failsafe:
      return "failsafe";
  }
  return "unknown";
}

}  // namespace softbake
