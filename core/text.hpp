#pragma once
/// Message building for errors and notes (GCC 12 has no <format>; core takes no dependency for it).

#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace softbake {

/// Streams every argument into one string: cat("body '", name, "': ", count, " pinned").
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

/// "a, b, c or d", each name between `quote`s: the alternatives of an error message.
inline std::string alternatives(const std::vector<std::string>& names,
                                std::string_view quote = "") {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i) text += i + 1 == names.size() ? " or " : ", ";
    text.append(quote).append(names[i]).append(quote);
  }
  return text;
}

}  // namespace softbake
