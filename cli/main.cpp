// The softbake command.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <unistd.h>

#include "bake/command_errors.hpp"
#include "bake/run_bake.hpp"
#include "bake/shell_quote.hpp"
#include "cli/bench_command.hpp"
#include "cli/compare_command.hpp"
#include "cli/export_command.hpp"
#include "cli/farm_command.hpp"
#include "cli/image_metrics.hpp"
#include "cli/scene_command.hpp"
#include "cli/verify_command.hpp"
#include "cli/wedge.hpp"
#include "core/scene/scene_setup.hpp"
#include "render/frame_renderer.hpp"

#ifndef SOFTBAKE_VERSION
#define SOFTBAKE_VERSION "unknown"
#endif

namespace {

/// What CLI11's help shows for a value of `spec`.
std::string typeName(const softbake::OptionSpec& spec) {
  switch (spec.kind) {
    case softbake::OptionKind::Whole:
      return "INT";
    case softbake::OptionKind::Number:
      return "NUMBER";
    case softbake::OptionKind::Choice:
      return "{" + CLI::detail::join(spec.choices(), ",") + "}";
    case softbake::OptionKind::Substeps:
      return "auto|INT";
    case softbake::OptionKind::ImageSize:
      return "WIDTHxHEIGHT";
    case softbake::OptionKind::Path:
      return "DIR";
    case softbake::OptionKind::Flag:
      break;
  }
  return "";
}

/// The options of the option table that `command` takes, added to `app`; each writes its value,
/// checked as the table checks it, into `given`. Those named in `lists` take several values,
/// comma-separated, and write them as an array (bench runs once per broad phase given).
void addTableOptions(CLI::App& app, unsigned command, softbake::GivenOptions& given,
                     std::initializer_list<std::string_view> lists = {}) {
  std::map<std::string_view, CLI::Option*> added;
  for (const softbake::OptionSpec& spec : softbake::optionTable()) {
    if (!(spec.commands & command)) continue;
    const std::string names =
        spec.shortFlag.empty() ? spec.flag() : std::string(spec.shortFlag) + "," + spec.flag();
    std::string help(spec.help);
    if (!spec.defaultText.empty()) help += " (default " + spec.defaultText + ")";
    const std::string name(spec.name);
    if (spec.kind == softbake::OptionKind::Flag) {
      added[spec.name] = app.add_flag_callback(
          names, [&given, name] { given[name] = true; }, help);
      continue;
    }
    const CLI::Validator check(
        [&spec](std::string& text) -> std::string {
          const auto error = softbake::checkOptionValue(spec, optionValueFromText(spec, text));
          return error ? error->message + ", got '" + text + "'" : std::string();
        },
        "", "");
    if (std::find(lists.begin(), lists.end(), spec.name) != lists.end()) {
      added[spec.name] = app.add_option_function<std::vector<std::string>>(
                                names,
                                [&given, &spec, name](const std::vector<std::string>& texts) {
                                  given[name] = softbake::GivenOptions::array();
                                  for (const std::string& text : texts)
                                    given[name].push_back(optionValueFromText(spec, text));
                                },
                                help + "; several, comma-separated, run one after the other")
                             ->delimiter(',')
                             ->check(check)
                             ->type_name(typeName(spec));
      continue;
    }
    added[spec.name] = app.add_option_function<std::string>(
                              names,
                              [&given, &spec, name](const std::string& text) {
                                given[name] = optionValueFromText(spec, text);
                              },
                              help)
                           ->check(check)
                           ->type_name(typeName(spec));
  }
  for (const softbake::OptionSpec& spec : softbake::optionTable())
    if (added.count(spec.name) && added.count(spec.excludes))
      added[spec.name]->excludes(added[spec.excludes]);
}

/// Of `words`, the one fewest single-character edits from `typed`, if it is within 2 (or a third of
/// its length); empty otherwise.
std::string nearestWord(const std::string& typed, const std::vector<std::string>& words) {
  std::string best;
  std::size_t bestDistance = std::max<std::size_t>(2, typed.size() / 3) + 1;
  for (const std::string& word : words) {
    std::vector<std::size_t> row(word.size() + 1);
    for (std::size_t j = 0; j <= word.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= typed.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= word.size(); ++j) {
        const std::size_t above = row[j];
        row[j] = std::min(
            {row[j] + 1, row[j - 1] + 1, diagonal + (typed[i - 1] == word[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    if (row[word.size()] < bestDistance) {
      bestDistance = row[word.size()];
      best = word;
    }
  }
  return best;
}

/// The command as typed, each word quoted for a POSIX shell where it needs it.
std::string shellCommandLine(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + softbake::shellQuoted(argv[i]);
  return line;
}

CLI::App* addRunCommand(CLI::App& app, softbake::RunOptions& run) {
  CLI::App* runApp = app.add_subcommand(
      "run",
      "Simulate a scene and write its frames. INPUT is a scene .json, a mesh file (any "
      "format assimp reads, dropped on the ground as a soft body), or nothing for the "
      "built-in default scene.");
  runApp->add_option("input", run.input, "scene .json or mesh file (default: built-in scene)");
  runApp->add_option("-o,--out", run.out, "output folder")->capture_default_str();
  addTableOptions(*runApp, softbake::kOptionRun, run.given);
  return runApp;
}

CLI::App* addExportCommand(CLI::App& app, softbake::ExportOptions& options) {
  CLI::App* exportApp = app.add_subcommand(
      "export",
      "Write frames of a run again from its simulation cache (OUT/cache), without simulating: "
      "the same files `run` writes for those frames, with the run's options. Outputs the run "
      "did not ask for can be made this way, and frame ranges can go to different machines.");
  exportApp->add_option("out", options.out, "the run's output folder (holding manifest.json)")
      ->required();
  exportApp->add_option("--frames", options.frames, "frames A:B, or A (default: all)");
  exportApp->add_flag("--obj", options.obj, "write the OBJ sequence");
  exportApp->add_flag("--vdb", options.vdb, "write the OpenVDB sequence");
  exportApp->add_flag("--png", options.png, "render the PNG sequence");
  exportApp
      ->add_option("--contacts-view", options.contactsView,
                   "render the PNG frames in this contact view, xray or opaque, instead of the "
                   "run's")
      ->check(CLI::IsMember(softbake::contactsViewNames()));
  exportApp->add_flag("--contacts", options.contacts, "write the contact JSON sequence");
  exportApp->add_flag("--pc2", options.pc2, "write the PC2 point caches (every frame)");
  exportApp->add_flag("--mdd", options.mdd, "write the MDD point caches (every frame)");
  exportApp->add_flag("--all", options.all,
                      "write every output the run's scene and options ask for");
  exportApp->add_option("-j,--threads", options.threads, "worker threads (0: all cores)")
      ->check(CLI::Range(0, 4096));
  exportApp->add_flag("-q,--quiet", options.quiet, "print errors and the final summary only");
  return exportApp;
}

/// The `run` options given after `--` to `wedge` and `farm`, read by `run`'s own parser so a
/// mistake is reported before anything is written. Throws softbake::Error with CLI11's message.
softbake::RunOptions parseRunArguments(const std::vector<std::string>& arguments) {
  CLI::App app;
  softbake::RunOptions run;
  addRunCommand(app, run);
  std::vector<std::string> words{"run", "wedge_scene.json"};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::reverse(words.begin(), words.end());  // CLI11 takes the arguments last first
  try {
    app.parse(words);
  } catch (const CLI::ParseError& error) {
    throw softbake::Error(std::string("the run options after --: ") + error.what());
  }
  softbake::landRunOptions(run);
  return run;
}

CLI::App* addWedgeCommand(CLI::App& app, softbake::WedgeOptions& options) {
  CLI::App* wedgeApp = app.add_subcommand(
      "wedge",
      "Bake every combination of some of a scene's keys: --vary bodies[0].material=rubber,jelly "
      "--vary settings.fps=24,48 makes 4 variant scenes in OUT/wedge_000 … with a table of what "
      "each sets (wedge.csv, wedge.md), and bakes them, several at once. Options after -- go to "
      "every `softbake run`.");
  wedgeApp->add_option("scene", options.input, "scene .json or built-in scene name")->required();
  wedgeApp->add_option("--vary", options.vary, "KEY.PATH=VALUE1,VALUE2,... (repeatable)")
      ->required()
      ->allow_extra_args(false);
  wedgeApp->add_option("-o,--out", options.out, "folder of the variants")->capture_default_str();
  wedgeApp->add_option("--parallel", options.parallel, "variants baked at once (default: cores)")
      ->check(CLI::Range(0, 4096));
  wedgeApp->add_flag(
      "--no-bake", [&options](std::int64_t) { options.bake = false; },
      "write the variants and the table only");
  wedgeApp->add_option("run_options", options.runArguments, "after --: options for `run`");
  return wedgeApp;
}

CLI::App* addFarmCommand(CLI::App& app, softbake::FarmOptions& options) {
  CLI::App* farm = app.add_subcommand(
      "farm", "Split a bake over a render farm's scheduler: `farm slurm` writes sbatch scripts.");
  farm->require_subcommand(1);
  CLI::App* slurm = farm->add_subcommand(
      "slurm",
      "Write Slurm sbatch scripts for SCENE (and its wedge): one simulation job per variant "
      "(`run --cache-only`), an array job per variant over chunks of frames that exports and "
      "renders them from the cache (afterok on its simulation), and a job that verifies every "
      "frame. Options after -- go to every `softbake run`.");
  slurm->add_option("scene", options.input, "scene .json or built-in scene name")->required();
  slurm->add_option("-o,--out", options.out, "output folder, on a file system all nodes share")
      ->capture_default_str();
  slurm->add_option("--vary", options.vary, "KEY.PATH=VALUE1,VALUE2,... as for `wedge`")
      ->allow_extra_args(false);
  slurm->add_option("--chunk", options.chunk, "frames per export task")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000000));
  slurm->add_option("--partition", options.partition, "Slurm partition of every job");
  slurm->add_option("--cpus-per-task", options.cpusPerTask, "CPUs of every job, and its threads")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  slurm->add_flag("--submit", options.submit, "submit the jobs with sbatch and print their ids");
  slurm->add_option("run_options", options.runArguments, "after --: options for `run`");
  return farm;
}

CLI::App* addVerifyCommand(CLI::App& app, softbake::VerifyOptions& options) {
  CLI::App* verify = app.add_subcommand(
      "verify",
      "Check a run's folder: every frame of every sequence its manifest lists there exactly "
      "once, whole and readable (cache frames by their checksums). Exit 0 when whole, 1 with "
      "every problem listed.");
  verify->add_option("out", options.out, "the run's output folder")->required();
  return verify;
}

CLI::App* addCompareCommand(CLI::App& app, softbake::CompareOptions& compare) {
  CLI::App* compareApp = app.add_subcommand(
      "compare",
      "Regression checks for CI: two rendered frames (PNG, EXR, TIFF), two folders of frames "
      "matched by name, or two bakes (run output folders or OBJ sequences), frame by frame. Exit "
      "0 within bounds, 1 when a frame differs or is missing, 2 on bad input.");
  compareApp->add_option("a", compare.a, "reference image, folder of frames or bake")->required();
  compareApp->add_option("b", compare.b, "new image, folder of frames or bake")->required();
  compareApp
      ->add_option("--metric", compare.metric,
                   "images: flip (perceptual, the default), pixel (largest channel difference, "
                   "0-255) or yee (OpenImageIO's compare_Yee)")
      ->check(CLI::IsMember(softbake::imageMetricNames()));
  const auto number = [&](const char* name, std::optional<double>& value, const char* help) {
    compareApp->add_option(name, value, help)->check(CLI::NonNegativeNumber);
  };
  number("--fail", compare.fail,
         "a pixel whose error is above this counts against the frame (flip 0.3, pixel 8)");
  number("--fail-percent", compare.failPercent,
         "a frame fails when more than this % of its pixels are above --fail (flip 0.05, pixel "
         "0.1, yee 0.75)");
  number("--fail-mean", compare.failMean,
         "a frame fails when its mean error is above this (flip 0.01)");
  number("--warn", compare.warn, "as --fail, for a warning (flip 0.2, pixel 8)");
  number("--warn-percent", compare.warnPercent, "as --fail-percent, for a warning");
  number("--warn-mean", compare.warnMean, "as --fail-mean, for a warning (flip 0.005)");
  compareApp
      ->add_option("--align", compare.align,
                   "pixels an edge may move and still match (default 1; 0 with --tolerance)")
      ->check(CLI::Range(0, 8));
  compareApp
      ->add_option("--tolerance", compare.tolerance,
                   "the pixel metric's --fail: largest channel difference (0-255) a matching pixel "
                   "may have, pixel against pixel (8)")
      ->check(CLI::Range(0, 255));
  compareApp
      ->add_option("--max-fraction", compare.maxFraction,
                   "the pixel metric's --fail-percent as a fraction of the pixels (0.001)")
      ->check(CLI::Range(0.0, 1.0));
  compareApp->add_option(
      "--diff", compare.diff,
      "write a heat map of the difference (a folder of them for folders) where frames differ");
  compareApp->add_option("--report", compare.report,
                         "write an HTML report into this folder: index.html and its images");
  compareApp->add_option("--junit", compare.junit,
                         "write JUnit XML to this file: a test case per frame");
  compareApp->add_flag("--update", compare.update,
                       "accept the new frames as the references (each file replaced atomically); "
                       "exit 0");
  const auto bakeLimit = [&](const char* name, double& value, const char* help) {
    compareApp->add_option(name, value, help)->capture_default_str()->check(CLI::NonNegativeNumber);
  };
  bakeLimit("--max-distance", compare.bake.maxDistance,
            "bakes: largest distance of a particle from where the reference has it, as a fraction "
            "of its body's size");
  bakeLimit("--max-rms", compare.bake.maxRms,
            "bakes: RMS distance of a body's particles, as a fraction of its size");
  bakeLimit("--max-volume-change", compare.bake.maxVolumeChange,
            "bakes: change of a body's volume, as a fraction of the reference's");
  bakeLimit("--max-contact-change", compare.bake.maxContactChange,
            "bakes: change of a body's contact count in a frame, as a fraction of the "
            "reference's (at least 1)");
  return compareApp;
}

CLI::App* addBenchCommand(CLI::App& app, softbake::BenchOptions& bench) {
  CLI::App* benchApp = app.add_subcommand(
      "bench",
      "Time a scene's simulation with no output files: per-stage median and p95 per step, "
      "contacts, peak memory and a machine-readable line per broad phase. SCENE is a scene "
      ".json, a mesh file or a built-in scene: default, balls1k, balls10k, balls100k, balls1m.");
  benchApp->add_option("scene", bench.input, "scene .json, mesh file or built-in scene name")
      ->required();
  addTableOptions(*benchApp, softbake::kOptionBench, bench.given, {"broadphase"});
  benchApp->add_option("--steps", bench.steps, "simulate exactly this many substeps")
      ->check(CLI::Range(1L, 1000000000L))
      ->excludes(benchApp->get_option("--frames"));
  benchApp
      ->add_option("--warmup", bench.warmupSteps,
                   "simulate this many steps first, unmeasured (to reach the contacts)")
      ->check(CLI::Range(0L, 1000000000L));
  benchApp->add_option("--csv", bench.csv, "write one row per step and broad phase to this file");
  benchApp->add_flag("--with-exports", bench.withExports,
                     "also time the OBJ and VDB writers and the PNG renderer per frame");
  benchApp->add_option("-o,--out", bench.out,
                       "folder for the --with-exports files (default: a temporary one, removed)");

  return benchApp;
}

#ifndef SOFTBAKE_COMPARE_PROGRAM
/// `softbake compare`: the program softbake-compare beside this one, in this process's place, with
/// the same arguments (cli/CMakeLists.txt says why it is a program of its own). Returns only when
/// it cannot be started: exit 2, as compare's bad input.
int runCompareProgram(char** argv) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::filesystem::path program = self.parent_path() / "softbake-compare";
  if (!error) {
    argv[0] = const_cast<char*>(program.c_str());
    ::execv(program.c_str(), argv);
  }
  const int why = error ? error.value() : errno;
  std::fprintf(stderr, "error: compare: cannot run %s: %s\n",
               error ? "softbake-compare (this program's path is unknown)" : program.c_str(),
               std::strerror(why));
  return 2;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f) then fails the write with EFBIG, which names the file, instead
  // of killing the process mid-frame.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"softbake " SOFTBAKE_VERSION
               " - offline soft-body simulation (Matyka-Ollila pressure bodies, Mesit-Guha "
               "collisions) with OBJ sequence output",
               "softbake"};
  app.set_version_flag("--version", std::string("softbake ") + SOFTBAKE_VERSION);
  app.footer(
      "Exit status: 0 done; 1 bad input (a file, key, flag or value; the message says which); 2 "
      "the simulation failed (it blew up); 3 an output could not be written (a full disk, a "
      "folder that cannot be made); 130 or 143 interrupted by SIGINT or SIGTERM (continue with "
      "`softbake run ... --resume`). `compare` has its own: 0 same, 1 different, 2 bad input.");
  app.require_subcommand(1);

  softbake::RunOptions run;
  CLI::App* runApp = addRunCommand(app, run);
  softbake::CompareOptions compare;
  CLI::App* compareApp = addCompareCommand(app, compare);
  softbake::BenchOptions bench;
  CLI::App* benchApp = addBenchCommand(app, bench);
  softbake::ExportOptions exportOptions;
  CLI::App* exportApp = addExportCommand(app, exportOptions);
  softbake::WedgeOptions wedge;
  CLI::App* wedgeApp = addWedgeCommand(app, wedge);
  softbake::FarmOptions farm;
  CLI::App* farmApp = addFarmCommand(app, farm);
  softbake::VerifyOptions verify;
  CLI::App* verifyApp = addVerifyCommand(app, verify);
  softbake::SceneCommandOptions scene;
  CLI::App* sceneApp = softbake::addSceneCommand(app, scene);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // A misspelt command gets the nearest one named; CLI11 only says one is required.
    std::vector<std::string> names;
    for (const CLI::App* command : app.get_subcommands({})) names.push_back(command->get_name());
    if (argc > 1 && argv[1][0] != '-' &&
        std::find(names.begin(), names.end(), argv[1]) == names.end()) {
      const std::string nearest = nearestWord(argv[1], names);
      std::fprintf(stderr, "softbake: no command '%s'%s; the commands are %s (softbake --help)\n",
                   argv[1], nearest.empty() ? "" : ("; did you mean '" + nearest + "'?").c_str(),
                   CLI::detail::join(names, ", ").c_str());
      return softbake::kExitBadInput;
    }
    // Bad usage is bad input: exit 1 (`compare`: 2, as its own contract says), not CLI11's 105-109.
    const int code = app.exit(error);
    return code == 0 ? 0 : (compareApp->parsed() ? 2 : softbake::kExitBadInput);
  }
  if (runApp->parsed()) {
    softbake::landRunOptions(run);
    run.commandLine = shellCommandLine(argc, argv);
    return softbake::runBake(run);
  }
  if (exportApp->parsed()) return softbake::exportCommand(exportOptions);
  if (wedgeApp->parsed() || farmApp->parsed()) {
    const std::vector<std::string>& extra =
        wedgeApp->parsed() ? wedge.runArguments : farm.runArguments;
    softbake::RunOptions parsed;
    const int status = softbake::reportingErrors([&] {
      parsed = parseRunArguments(extra);
      return 0;
    });
    if (status != 0) return status;
    if (wedgeApp->parsed()) return softbake::wedgeCommand(wedge);
    farm.run = parsed;
    return softbake::farmSlurmCommand(farm);
  }
  if (verifyApp->parsed()) return softbake::verifyCommand(verify);
#ifdef SOFTBAKE_COMPARE_PROGRAM
  if (compareApp->parsed()) return softbake::compareCommand(compare);
#else
  if (compareApp->parsed()) return runCompareProgram(argv);
#endif
  if (benchApp->parsed()) {
    softbake::applyLoadOptions(bench.given, bench.load);
    bench.threads = bench.given.value("threads", 0);
    return softbake::benchCommand(bench);
  }
  if (sceneApp->parsed()) return softbake::sceneCommand(scene);
  return 0;
}
