#pragma once
/// `softbake run`: load a scene (or a mesh, or the built-in default), simulate it, and write the
/// frame sequences while the simulation goes on.

#include "cli/run_options.hpp"

namespace softbake {

/// Runs the job; returns the process exit code. Errors are printed, never thrown.
int runCommand(const RunOptions& options);

}  // namespace softbake
