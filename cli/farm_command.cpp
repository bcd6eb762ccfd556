#include "cli/farm_command.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>

#include "bake/command_errors.hpp"
#include "bake/run_outputs.hpp"
#include "bake/scene_input.hpp"
#include "bake/shell_quote.hpp"
#include "cli/wedge.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

/// Slurm's default MaxArraySize is 1001: task ids 0…1000.
constexpr int kMaxArrayTasks = 1001;

struct FarmVariant {
  std::string name;   ///< "wedge_000", or the scene's name without a wedge
  fs::path folder;    ///< where its run writes, absolute
  std::string scene;  ///< absolute scene file, or a built-in name
  int frames = 0;
};

std::string words(const std::vector<std::string>& list) {
  std::string line;
  for (const std::string& word : list) line += cat(" ", shellQuoted(word));
  return line;
}

/// The #SBATCH lines every job shares; the caller adds its own, then the commands.
std::string header(const FarmOptions& options, const std::string& jobName, const fs::path& logs,
                   const std::string& logPattern) {
  std::string text = "#!/bin/bash\n";
  text += cat("#SBATCH --job-name=", jobName, "\n");
  text += cat("#SBATCH --output=", (logs / logPattern).string(), "\n");
  text += cat("#SBATCH --chdir=", fs::absolute(options.out).lexically_normal().string(), "\n");
  text += cat("#SBATCH --cpus-per-task=", options.cpusPerTask, "\n");
  if (options.partition) text += cat("#SBATCH --partition=", *options.partition, "\n");
  return text;
}

/// sbatch reads #SBATCH lines only up to the first command.
constexpr const char* kStrict = "set -euo pipefail\n";

void writeScript(const fs::path& path, const std::string& text) {
  writeFileAtomically(path, text);
  ::chmod(path.c_str(), 0755);
}

}  // namespace

int farmSlurmCommand(const FarmOptions& options) {
  return reportingErrors([&] {
    if (options.chunk < 1) throw Error("--chunk: expected at least 1 frame per task");
    const fs::path out = fs::absolute(options.out).lexically_normal();
    std::error_code error;
    const fs::path binary = fs::read_symlink("/proc/self/exe", error);
    if (error) throw Error(cat("cannot find the softbake binary: ", error.message()));

    // The variants, each with its frame count as the run will see it.
    std::vector<FarmVariant> variants;
    if (options.vary.empty()) {
      const bool file = fs::is_regular_file(options.input, error);
      variants.push_back(
          {"", out, file ? fs::absolute(options.input).lexically_normal().string() : options.input,
           0});
    } else {
      std::vector<WedgeVariation> variations;
      for (const std::string& text : options.vary) variations.push_back(parseVariation(text));
      for (const PreparedVariant& variant : prepareWedge(options.input, variations, out))
        variants.push_back({variant.name, variant.folder, variant.scene.string(), 0});
    }
    for (FarmVariant& variant : variants) {
      SceneFile scene = loadSceneInput(variant.scene, options.run.load);
      applySceneOptions(options.run.given, scene);
      variant.frames = scene.setup.settings.frames;
      if (variant.name.empty()) variant.name = scene.setup.name;
      const int tasks = (variant.frames + options.chunk - 1) / options.chunk;
      if (tasks > kMaxArrayTasks)
        throw Error(cat(variant.name, ": ", variant.frames, " frames in chunks of ", options.chunk,
                        " make ", tasks,
                        " array tasks, more than Slurm's default MaxArraySize "
                        "allows (",
                        kMaxArrayTasks, "); raise --chunk"));
    }

    const fs::path slurm = out / "slurm", logs = slurm / "logs";
    makeDirectories(logs);
    const std::string softbake = shellQuoted(binary.string());
    const std::string threads = cat(" -j ", options.cpusPerTask);
    std::string submit =
        "#!/bin/sh\n"
        "# Submits the bake: each simulation, its export array after it, the check after all.\n"
        "set -eu\n"
        "cd \"$(dirname \"$0\")\"\n"
        "id() { sbatch --parsable \"$@\" | cut -d';' -f1; }\n";
    std::string exportIds;
    std::string verifyFolders;
    for (const FarmVariant& variant : variants) {
      const std::string folder = shellQuoted(variant.folder.string());
      const std::string simulate = cat("simulate_", variant.name, ".sbatch");
      // A requeued or resubmitted simulation continues where it stopped.
      writeScript(slurm / simulate,
                  header(options, cat("softbake-simulate-", variant.name), logs, "%x_%j.out") +
                      cat(kStrict, "resume=\nif [ -f ", folder,
                          "/manifest.json ]; then resume=--resume; fi\n", "exec ", softbake,
                          " run ", shellQuoted(variant.scene), " -o ", folder, " --cache-only",
                          threads, " -q", words(options.runArguments), " $resume\n"));
      const int tasks = (variant.frames + options.chunk - 1) / options.chunk;
      const std::string exporting = cat("export_", variant.name, ".sbatch");
      writeScript(
          slurm / exporting,
          header(options, cat("softbake-export-", variant.name), logs, "%x_%A_%a.out") +
              cat("#SBATCH --array=0-", tasks - 1, "\n", kStrict, "first=$((SLURM_ARRAY_TASK_ID * ",
                  options.chunk, " + 1))\n", "last=$((first + ", options.chunk - 1, "))\n",
                  "if [ \"$last\" -gt ", variant.frames, " ]; then last=", variant.frames, "; fi\n",
                  "exec ", softbake, " export ", folder, " --all --frames \"$first:$last\"",
                  threads, " -q\n"));
      const std::string tag = cat("sim_", variant.name);
      submit += cat(tag, "=$(id ", simulate, ")\n", "export_", variant.name,
                    "=$(id --dependency=afterok:$", tag, " ", exporting, ")\n", "echo \"",
                    variant.name, ": simulate $", tag, ", export $export_", variant.name, " (",
                    tasks, " tasks of ", options.chunk, " frames)\"\n");
      exportIds += cat(":$export_", variant.name);
      verifyFolders += cat(" ", folder);
    }
    writeScript(slurm / "verify.sbatch",
                header(options, "softbake-verify", logs, "%x_%j.out") +
                    cat(kStrict, "status=0\nfor folder in", verifyFolders, "; do\n  ", softbake,
                        " verify \"$folder\" || status=1\ndone\nexit $status\n"));
    submit += cat("verify=$(id --dependency=afterok", exportIds, " verify.sbatch)\n",
                  "echo \"verify: $verify\"\n");
    writeScript(slurm / "submit.sh", submit);

    std::printf(
        "farm: %zu simulation jobs, %zu export arrays in chunks of %d frames, 1 check; "
        "scripts in %s\n",
        variants.size(), variants.size(), options.chunk, slurm.string().c_str());
    if (!options.submit) {
      std::printf("submit with: %s\n", shellQuoted((slurm / "submit.sh").string()).c_str());
      return 0;
    }
    std::fflush(stdout);
    const int status = std::system(shellQuoted((slurm / "submit.sh").string()).c_str());
    if (status != 0)
      throw Error(cat((slurm / "submit.sh").string(), " failed (is sbatch on the PATH?)"));
    return 0;
  });
}

}  // namespace softbake
