#pragma once
/// `softbake farm slurm SCENE --out DIR [--vary …] [--chunk N] [--partition P] [--submit]`: a
/// bake split the way a studio farm splits it, as sbatch scripts for Slurm.
///
///   simulate  one job per variant: `run --cache-only`, the simulation and its cache, in order
///   export    per variant, an array job over chunks of frames (afterok on its simulation):
///             `export --all --frames A:B`, every output the scene asks for, from the cache
///   verify    one job after all of them: `verify` on every variant's folder, every frame's
///             files there exactly once, whole and readable
///
/// The scripts are in DIR/slurm/ with submit.sh, which submits them in order with their
/// dependencies and prints the job ids; --submit runs it. Each task logs to its own file in
/// DIR/slurm/logs/. Paths in the scripts are absolute, so DIR must be on a file system every
/// node shares.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bake/run_bake.hpp"

namespace softbake {

struct FarmOptions {
  std::string input;
  std::filesystem::path out = "farm";
  std::vector<std::string> vary;          ///< as for `wedge`; none: the scene alone
  int chunk = 16;                         ///< frames per export task
  std::optional<std::string> partition;   ///< #SBATCH --partition
  int cpusPerTask = 1;                    ///< #SBATCH --cpus-per-task, and `-j` of each command
  bool submit = false;                    ///< run submit.sh
  std::vector<std::string> runArguments;  ///< passed to every `softbake run`
  RunOptions run;                         ///< the same, parsed: frames and outputs per variant
};

/// Returns the process exit code. Errors are printed, never thrown.
int farmSlurmCommand(const FarmOptions& options);

}  // namespace softbake
