#pragma once
/// The one exception type softbake throws for bad input. Its message is complete and meant for the
/// user: it names the file, key path, body or frame, and says what is wrong.

#include <stdexcept>
#include <string>

namespace softbake {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace softbake
