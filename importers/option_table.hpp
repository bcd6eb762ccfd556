#pragma once
/// Every option of a bake, in one table: its flag, its Python keyword, the scene key it overrides,
/// its range or choices, its help text and where it lands. The command line's options
/// (cli/main.cpp), the keywords of Python's run() and Simulation() (python/run_options.cpp), the
/// checks of the scene keys (scene_file.cpp) and the run's record in its manifest
/// (bake/run_record.cpp) are all made from it, so an option is added in one place.
///
/// Values travel as JSON, as a scene file holds them: what a command line or a keyword gives is
/// turned into the JSON value its scene key takes ("4" into 4, "1280x720" into [1280, 720]), and
/// one check serves them all.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "importers/scene_file.hpp"

namespace softbake {

/// What a value is.
enum class OptionKind {
  Flag,       ///< given or not; lands `OptionSpec::value` (true, or the value it stands for)
  Whole,      ///< an integer in [low, high]
  Number,     ///< a finite number in [low, high], or in (low, high] when `aboveLow`
  Choice,     ///< one of `choices()`
  Substeps,   ///< "auto", or an integer in [low, high]
  ImageSize,  ///< [width, height] (on a command line WIDTHxHEIGHT), each in [low, high]
  Path,       ///< a file or folder
};

/// The commands that take an option, as bits.
enum OptionCommand : unsigned {
  kOptionRun = 1,         ///< softbake run, and Python's run()
  kOptionBench = 2,       ///< softbake bench
  kOptionSimulation = 4,  ///< Python's Simulation(): what shapes the simulation and its loading
};

/// Where a value lands once checked.
///  - a scene key (`sceneKey`): written over the scene's own value after it is loaded, read and
///    checked as a scene file's value is;
///  - a field of SceneLoadOptions (`load`): in force while the scene loads;
///  - otherwise one of the run's own settings, which the command that owns it reads
///    (bake/run_options.cpp lands them in RunOptions).
using LoadField =
    std::variant<std::monostate, bool SceneLoadOptions::*,
                 std::optional<std::uint64_t> SceneLoadOptions::*, std::size_t SceneLoadOptions::*>;

struct OptionSpec {
  std::string_view name;       ///< the flag without "--"; the manifest's record key
  std::string_view shortFlag;  ///< "-j", or empty
  OptionKind kind;
  std::string_view help;
  unsigned commands;
  std::string_view sceneKey = {};  ///< "settings.collisions.levels", or empty
  LoadField load = {};
  double low = 0, high = 0;
  bool aboveLow = false;
  std::vector<std::string> (*choices)() = nullptr;
  nlohmann::json value = true;     ///< what a Flag lands
  std::string_view excludes = {};  ///< the name of an option it cannot be given with
  /// Recorded in the manifest: it shapes the run's files, so `--resume` compares it and `export`
  /// rebuilds the writers with it.
  bool recorded = false;
  std::string defaultText = {};  ///< shown in --help

  std::string flag() const { return "--" + std::string(name); }
  /// The Python keyword: the name with '_' for '-'.
  std::string keyword() const;
};

/// The table, in the order --help lists the options.
const std::vector<OptionSpec>& optionTable();

/// The row named `name`; throws std::logic_error for none, a mistake in the code.
const OptionSpec& optionSpec(std::string_view name);

/// The flag that says no to `spec` (--no-render for --render: named "no-" + its name, and
/// excluding it), or null. Python takes the pair as one keyword: render=False is --no-render.
const OptionSpec* negationOf(const OptionSpec& spec);
bool isNegation(const OptionSpec& spec);

/// Where `spec`'s scene key is in a scene document: settings.fps is /settings/fps.
nlohmann::json::json_pointer sceneKeyPointer(const OptionSpec& spec);

/// Why `value` is not one `spec` takes, or nothing when it is.
struct OptionValueError {
  bool wrongType;       ///< a value of another type (Python's TypeError) rather than out of range
  std::string message;  ///< "expected a whole number from 0 to 8"
};
/// `quote` quotes the choices: '"' in a scene file, '\'' on a command line or in Python.
std::optional<OptionValueError> checkOptionValue(const OptionSpec& spec,
                                                 const nlohmann::json& value, char quote = '\'');

/// The JSON value a command line's `text` stands for: "4" → 4, "auto" → "auto", "1280x720" →
/// [1280, 720]. Not checked: text that is no such value comes back as the string, for
/// checkOptionValue() to refuse.
nlohmann::json optionValueFromText(const OptionSpec& spec, std::string_view text);

/// The command-line words that give `value`: {"--levels", "3"}, {"--vdb"}.
std::vector<std::string> optionWords(const OptionSpec& spec, const nlohmann::json& value);

/// Options as given: name → checked value. Whoever reads them goes through the table, in its
/// order, so the order they came in does not matter.
using GivenOptions = nlohmann::json;

/// Sets `given[spec.name]` to `value` after checking it; throws softbake::Error
/// "--levels: expected a whole number from 0 to 8, got 9".
void giveOption(GivenOptions& given, const OptionSpec& spec, const nlohmann::json& value);

/// Writes the given options that land in the scene over its values (in the table's order, so
/// --no-response comes after --response) and those that land in SceneLoadOptions into `load`.
void applySceneOptions(const GivenOptions& given, SceneFile& scene);
void applyLoadOptions(const GivenOptions& given, SceneLoadOptions& load);

}  // namespace softbake
