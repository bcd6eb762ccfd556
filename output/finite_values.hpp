#pragma once
/// Refusing numbers that are not finite before they reach a file. A NaN in an OBJ or a VDB
/// poisons every tool downstream, and JSON cannot hold one at all: nlohmann writes `null`, so a
/// reader would see a missing value instead of an error. Every writer checks what it is about to
/// write, and fails before the file exists.

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <string_view>

#include <Eigen/Core>

#include "core/text.hpp"
#include "output/frame.hpp"

namespace softbake {

/// Throws softbake::Error "<file>: not written: <what> is not finite (<components>)".
[[noreturn]] void refuseNonFinite(const std::filesystem::path& file, std::string_view what,
                                  std::initializer_list<double> components);

/// refuseNonFinite() when a component of `value` is NaN or infinite. `describe()` says what the
/// value is ("frame 7: body 'ball': particle 5's position"); it runs only then, so the check
/// costs nothing in a writer's inner loop.
template <class Derived, class Describe>
void requireFinite(const std::filesystem::path& file, const Eigen::MatrixBase<Derived>& value,
                   Describe&& describe) {
  if (value.allFinite()) [[likely]]
    return;
  if constexpr (Derived::SizeAtCompileTime == 2)
    refuseNonFinite(file, describe(), {double(value[0]), double(value[1])});
  else
    refuseNonFinite(file, describe(), {double(value[0]), double(value[1]), double(value[2])});
}

/// The same for one number.
template <class Describe>
void requireFinite(const std::filesystem::path& file, double value, Describe&& describe) {
  if (std::isfinite(value)) [[likely]]
    return;
  refuseNonFinite(file, describe(), {value});
}

/// requireFinite() on the position and the normal of every contact of `frame`; `name(i)` names
/// contact i in the message ("contact 3", or with its surfaces).
template <class Name>
void requireFiniteContacts(const std::filesystem::path& file, const Frame& frame, Name&& name) {
  for (std::size_t i = 0; i < frame.contacts.size(); ++i) {
    const auto describe = [&](std::string_view what) {
      return cat("frame ", frame.number, ": the ", what, " of ", name(i));
    };
    requireFinite(file, frame.contacts[i].position, [&] { return describe("position"); });
    requireFinite(file, frame.contacts[i].normal, [&] { return describe("normal"); });
  }
}

}  // namespace softbake
