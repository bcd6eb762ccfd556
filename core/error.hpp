#pragma once
/// The exceptions softbake throws. Every message is complete and meant for the user: it names the
/// file, key path, body or frame, and says what is wrong. The kind decides the command's exit
/// status: bad input 1, a simulation that failed 2, an output that could not be written 3.

#include <stdexcept>
#include <string>

namespace softbake {

/// Bad input, or anything not more specific below.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// The input was valid, but the simulation could not go on: it blew up.
class SimulationFailure : public Error {
 public:
  using Error::Error;
};

/// An output could not be written: a full disk, a folder that cannot be made, a failed write.
class OutputFailure : public Error {
 public:
  using Error::Error;
};

}  // namespace softbake
