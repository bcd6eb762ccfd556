#pragma once
/// A bake, as `softbake run` and Python's `softbake.run()` ask for it: load a scene (or a mesh, or
/// the built-in default), simulate it into the cache while the writers write each frame, render
/// from the cache, and report.

#include "bake/run_options.hpp"

namespace softbake {

/// Runs the bake; returns the process exit code. Errors are printed, never thrown.
int runBake(const RunOptions& options);

}  // namespace softbake
