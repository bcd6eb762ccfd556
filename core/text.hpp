#pragma once
/// Message building for errors and notes (GCC 12 has no <format>; core takes no dependency for it).

#include <sstream>
#include <string>

namespace softbake {

/// Streams every argument into one string: cat("body '", name, "': ", count, " pinned").
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

}  // namespace softbake
