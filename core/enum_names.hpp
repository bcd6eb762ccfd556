#pragma once
/// The user-facing names of a settings enum (broad phase, response, integrator): one list of
/// kinds in core, one name per kind, so the scene parser, the command line and the messages
/// stay in step.

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace softbake {

/// The names of `kinds`, in order.
template <class Kind, class NameOf>
std::vector<std::string> namesOf(std::span<const Kind> kinds, NameOf nameOf) {
  std::vector<std::string> names;
  for (Kind kind : kinds) names.emplace_back(nameOf(kind));
  return names;
}

/// Sets `kind` to the one of `kinds` named `name`; false when none is.
template <class Kind, class NameOf>
bool parseNamed(std::string_view name, std::span<const Kind> kinds, NameOf nameOf, Kind& kind) {
  for (Kind candidate : kinds)
    if (nameOf(candidate) == name) {
      kind = candidate;
      return true;
    }
  return false;
}

}  // namespace softbake
