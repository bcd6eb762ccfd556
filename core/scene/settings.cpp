#include "core/scene/settings.hpp"

#include <span>

#include "core/enum_names.hpp"

namespace softbake {

std::string_view broadPhaseName(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::Sbhash:
      return "sbhash";
    case BroadPhaseKind::SpatialHash:
      return "spatialhash";
    case BroadPhaseKind::Bvh:
      return "bvh";
    case BroadPhaseKind::BruteForce:
      return "brute";
  }
  return "unknown";
}

std::vector<std::string> broadPhaseNames() {
  return namesOf(std::span<const BroadPhaseKind>(kBroadPhaseKinds), broadPhaseName);
}

bool parseBroadPhase(std::string_view name, BroadPhaseKind& kind) {
  return parseNamed(name, std::span<const BroadPhaseKind>(kBroadPhaseKinds), broadPhaseName, kind);
}

std::string_view responseModeName(ResponseMode mode) {
  switch (mode) {
    case ResponseMode::TwoSided:
      return "two-sided";
    case ResponseMode::Paper:
      return "paper";
    case ResponseMode::None:
      return "none";
  }
  return "two-sided";
}

std::vector<std::string> responseModeNames() {
  return namesOf(std::span<const ResponseMode>(kResponseModes), responseModeName);
}

bool parseResponseMode(std::string_view name, ResponseMode& mode) {
  return parseNamed(name, std::span<const ResponseMode>(kResponseModes), responseModeName, mode);
}

std::string_view initialOverlapModeName(InitialOverlapMode mode) {
  switch (mode) {
    case InitialOverlapMode::SetAside:
      return "set_aside";
    case InitialOverlapMode::Separate:
      return "separate";
    case InitialOverlapMode::Ignore:
      return "ignore";
  }
  return "set_aside";
}

std::vector<std::string> initialOverlapModeNames() {
  return namesOf(std::span<const InitialOverlapMode>(kInitialOverlapModes), initialOverlapModeName);
}

bool parseInitialOverlapMode(std::string_view name, InitialOverlapMode& mode) {
  return parseNamed(name, std::span<const InitialOverlapMode>(kInitialOverlapModes),
                    initialOverlapModeName, mode);
}

std::string_view integratorName(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::Implicit:
      return "implicit";
    case IntegratorKind::Xpbd:
      return "xpbd";
    case IntegratorKind::Explicit:
      break;
  }
  return "explicit";
}

std::vector<std::string> integratorNames() {
  return namesOf(std::span<const IntegratorKind>(kIntegratorKinds), integratorName);
}

bool parseIntegrator(std::string_view name, IntegratorKind& kind) {
  return parseNamed(name, std::span<const IntegratorKind>(kIntegratorKinds), integratorName, kind);
}

std::string_view contactsViewName(ContactsView view) {
  switch (view) {
    case ContactsView::XRay:
      return "xray";
    case ContactsView::Opaque:
      return "opaque";
    case ContactsView::Automatic:
      break;
  }
  return "automatic";
}

std::vector<std::string> contactsViewNames() {
  return {std::string(contactsViewName(ContactsView::XRay)),
          std::string(contactsViewName(ContactsView::Opaque))};
}

ContactsView parseContactsView(std::string_view name) {
  for (const ContactsView view : {ContactsView::XRay, ContactsView::Opaque})
    if (name == contactsViewName(view)) return view;
  return ContactsView::Automatic;
}

}  // namespace softbake
