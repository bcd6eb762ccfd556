#pragma once
/// Words for a POSIX shell: the command a user can paste to resume a run, the farm's scripts.

#include <string>

namespace softbake {

/// `word` as one shell word: as it is when it holds only characters no shell treats specially,
/// else in single quotes.
inline std::string shellQuoted(const std::string& word) {
  const bool plain = !word.empty() && word.find_first_not_of(
                                          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                          "0123456789-_./=:,+@%") == std::string::npos;
  if (plain) return word;
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace softbake
