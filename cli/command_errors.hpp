#pragma once
/// How every command ends on an error: the message on stderr after a blank line (so it stands
/// apart from a progress bar), exit code 1.

#include <cstdio>
#include <filesystem>
#include <new>

#include "core/error.hpp"

namespace softbake {

/// Runs `command` and returns its exit code, or 1 after printing a softbake::Error, a file-system
/// error or an allocation failure.
template <class Command>
int reportingErrors(Command&& command) {
  const auto report = [](const char* message) {
    std::fflush(stdout);
    std::fprintf(stderr, "\nsoftbake: error: %s\n", message);
    return 1;
  };
  try {
    return command();
  } catch (const Error& error) {
    return report(error.what());
  } catch (const std::filesystem::filesystem_error& error) {
    return report(error.what());
  } catch (const std::bad_alloc&) {
    return report("out of memory; try a smaller scene");
  }
}

}  // namespace softbake
