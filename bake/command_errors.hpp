#pragma once
/// How every command ends on an error: the message on stderr after a blank line (so it stands
/// apart from a progress bar), and the exit status of the contract (docs/commands.md, --help):
///   0  done
///   1  bad input: a file, key, flag or value that is wrong (the message says which)
///   2  the simulation failed: it blew up
///   3  an output could not be written: a full disk, a folder that cannot be made
///   130, 143  interrupted by SIGINT or SIGTERM (128 + the signal), resumable with --resume

#include <cstdio>
#include <filesystem>
#include <new>

#include "core/error.hpp"

namespace softbake {

inline constexpr int kExitBadInput = 1, kExitSimulationFailed = 2, kExitOutputFailed = 3;

/// Runs `command` and returns its exit code, or the contract's status after printing a
/// softbake::Error, a file-system error or an allocation failure.
template <class Command>
int reportingErrors(Command&& command) {
  const auto report = [](const char* message, int status) {
    std::fflush(stdout);
    std::fprintf(stderr, "\nsoftbake: error: %s\n", message);
    return status;
  };
  try {
    return command();
  } catch (const SimulationFailure& error) {
    return report(error.what(), kExitSimulationFailed);
  } catch (const OutputFailure& error) {
    return report(error.what(), kExitOutputFailed);
  } catch (const Error& error) {
    return report(error.what(), kExitBadInput);
  } catch (const std::filesystem::filesystem_error& error) {
    return report(error.what(), kExitOutputFailed);
  } catch (const std::bad_alloc&) {
    return report("out of memory; try a smaller scene", kExitBadInput);
  }
}

}  // namespace softbake
