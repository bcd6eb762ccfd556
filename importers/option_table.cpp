#include "importers/option_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

constexpr unsigned kSimulate = kOptionRun | kOptionBench | kOptionSimulation;
constexpr unsigned kRunSimulation = kOptionRun | kOptionSimulation;

std::vector<std::string> vdbCompressions() {
  return {"zip", "blosc", "none"};
}
std::vector<std::string> upAxes() {
  return {"y", "z"};
}

// Each row names only the columns it sets; GCC 12 warns of every column a designated initializer
// leaves to its default.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
std::vector<OptionSpec> makeTable() {
  using K = OptionKind;
  const ImportLimits limits;
  return {
      // How the scene loads.
      {.name = "accept-lossy-import",
       .kind = K::Flag,
       .help = "import what is left of a mesh file that lost geometry on the way (faces assimp "
               "dropped, unused vertices, fewer rows than the header says), with a warning, "
               "instead of refusing it",
       .commands = kSimulate,
       .load = &SceneLoadOptions::acceptLossyImport,
       .recorded = true},
      {.name = "max-vertices",
       .kind = K::Whole,
       .help = "most vertices one mesh file may bring in",
       .commands = kSimulate,
       .load = &SceneLoadOptions::maxVertices,
       .low = 1,
       .high = 0x1p62,
       .recorded = true,
       .defaultText = std::to_string(limits.maxVertices)},
      {.name = "max-faces",
       .kind = K::Whole,
       .help = "most triangles one mesh file may bring in",
       .commands = kSimulate,
       .load = &SceneLoadOptions::maxFaces,
       .low = 1,
       .high = 0x1p62,
       .recorded = true,
       .defaultText = std::to_string(limits.maxFaces)},
      {.name = "max-import-memory",
       .kind = K::Whole,
       .help = "most memory one mesh file's import may take, MiB; the process reading it with "
               "assimp is held to it too",
       .commands = kSimulate,
       .load = &SceneLoadOptions::maxImportMemoryMib,
       .low = 1,
       .high = 0x1p40,
       .recorded = true,
       .defaultText = "half of this machine's memory"},
      {.name = "max-import-seconds",
       .kind = K::Whole,
       .help = "most seconds reading one mesh file with assimp may take",
       .commands = kSimulate,
       .load = &SceneLoadOptions::maxImportSeconds,
       .low = 1,
       .high = double(kMaxImportSeconds),
       .recorded = true,
       .defaultText = std::to_string(limits.maxSeconds)},
      {.name = "max-bodies",
       .kind = K::Whole,
       .help = "most bodies the scene may have",
       .commands = kSimulate,
       .load = &SceneLoadOptions::maxBodies,
       .low = 1,
       .high = 0x1p40,
       .recorded = true,
       .defaultText = std::to_string(SceneLoadOptions().maxBodies)},

      // The simulation.
      {.name = "frames",
       .kind = K::Whole,
       .help = "number of frames to simulate",
       .commands = kSimulate,
       .sceneKey = "settings.frames",
       .low = 1,
       .high = 10'000'000,
       .recorded = true},
      {.name = "fps",
       .kind = K::Number,
       .help = "frames per second",
       .commands = kRunSimulation,
       .sceneKey = "settings.fps",
       .low = 0,
       .high = 1e6,
       .aboveLow = true,
       .recorded = true},
      {.name = "integrator",
       .kind = K::Choice,
       .help = "implicit (backward Euler, the default), explicit (the paper's Euler, to "
               "reproduce its figures) or xpbd (position-based, small steps); implicit and xpbd "
               "are stable at any step",
       .commands = kSimulate,
       .sceneKey = "settings.integrator",
       .choices = integratorNames,
       .recorded = true},
      {.name = "substeps",
       .kind = K::Substeps,
       .help = "substeps per frame, or 'auto'",
       .commands = kSimulate,
       .sceneKey = "settings.substeps",
       .low = 1,
       .high = 1 << 30,
       .recorded = true},
      {.name = "broadphase",
       .kind = K::Choice,
       .help = "collision broad phase: sbhash (the paper's subdivided boxes and box hash), "
               "spatialhash, bvh or brute",
       .commands = kSimulate,
       .sceneKey = "settings.collisions.broadphase",
       .choices = broadPhaseNames,
       .recorded = true},
      {.name = "levels",
       .kind = K::Whole,
       .help = "subdivision level of the sbhash boxes",
       .commands = kSimulate,
       .sceneKey = "settings.collisions.levels",
       .low = 0,
       .high = 8,
       .recorded = true},
      {.name = "response",
       .kind = K::Choice,
       .help = "collision response: two-sided (momentum-conserving), paper (only the particle "
               "moves) or none",
       .commands = kRunSimulation,
       .sceneKey = "settings.collisions.response",
       .choices = responseModeNames,
       .recorded = true},
      {.name = "no-response",
       .kind = K::Flag,
       .help = "detect contacts but do not respond (the paper's figure 5b)",
       .commands = kRunSimulation,
       .sceneKey = "settings.collisions.response",
       .value = "none",
       .recorded = true},
      {.name = "no-pair-cache",
       .kind = K::Flag,
       .help = "run the broad phase every substep instead of reusing its pairs (same result; "
               "bench: to compare the broad phases themselves)",
       .commands = kSimulate,
       .sceneKey = "settings.collisions.pair_cache",
       .value = false,
       .recorded = true},

      {.name = "no-self-collision",
       .kind = K::Flag,
       .help = "bodies whose scene entry does not ask for it collide with others but not with "
               "themselves: 1.1-1.5x faster for bodies that cannot fold (balls, blocks)",
       .commands = kSimulate,
       .sceneKey = "settings.collisions.self_collision",
       .value = false,
       .recorded = true},

      // The outputs.
      {.name = "frame-padding",
       .kind = K::Whole,
       .help = "digits of the frame number in names",
       .commands = kOptionRun,
       .sceneKey = "output.frame_padding",
       .low = 1,
       .high = 9,
       .recorded = true},
      {.name = "contacts",
       .kind = K::Flag,
       .help = "write each frame's contacts to OUT/contacts/<scene>_0001.json ...",
       .commands = kOptionRun,
       .sceneKey = "output.contacts",
       .recorded = true},
      {.name = "render",
       .kind = K::Flag,
       .help = "render PNG frames with EGL off screen (on by default for the built-in scene)",
       .commands = kOptionRun,
       .sceneKey = "output.png",
       .recorded = true},
      {.name = "no-render",
       .kind = K::Flag,
       .help = "write no PNG frames",
       .commands = kOptionRun,
       .sceneKey = "output.png",
       .value = false,
       .excludes = "render",
       .recorded = true},
      {.name = "size",
       .kind = K::ImageSize,
       .help = "PNG size, WIDTHxHEIGHT",
       .commands = kOptionRun,
       .sceneKey = "render.size",
       .low = 16,
       .high = 16384,
       .recorded = true,
       .defaultText = "1280x720"},
      {.name = "no-contact-spheres",
       .kind = K::Flag,
       .help = "render without the spheres at the contact points",
       .commands = kOptionRun,
       .sceneKey = "render.contact_spheres",
       .value = false,
       .recorded = true},
      {.name = "contacts-view",
       .kind = K::Choice,
       .help = "xray: bodies translucent, so the contacts inside show (the default when contact "
               "spheres are drawn and bodies can touch each other or themselves); opaque: bodies "
               "solid",
       .commands = kOptionRun,
       .sceneKey = "render.contacts_view",
       .choices = contactsViewNames,
       .recorded = true},
      {.name = "render-while-simulating",
       .kind = K::Flag,
       .help = "render each frame as it is simulated, the camera framed on the first frame, "
               "instead of from the cache after the simulation, framed on the whole shot",
       .commands = kOptionRun,
       .recorded = true},
      {.name = "vdb",
       .kind = K::Flag,
       .help = "write OpenVDB level sets, velocity and contacts per frame",
       .commands = kOptionRun,
       .sceneKey = "output.vdb",
       .recorded = true},
      {.name = "pc2",
       .kind = K::Flag,
       .help = "write a PC2 point cache per body (OUT/pc2) and its rest mesh (OUT/cache_mesh): "
               "Blender's Mesh Cache and 3ds Max's Point Cache modifiers play them",
       .commands = kOptionRun,
       .sceneKey = "output.pc2",
       .recorded = true},
      {.name = "mdd",
       .kind = K::Flag,
       .help = "write an MDD point cache per body (OUT/mdd), as --pc2",
       .commands = kOptionRun,
       .sceneKey = "output.mdd",
       .recorded = true},
      {.name = "voxel-size",
       .kind = K::Number,
       .help = "VDB voxel size in scene units",
       .commands = kOptionRun,
       .low = 0,
       .high = HUGE_VAL,
       .aboveLow = true,
       .recorded = true,
       .defaultText = "half the mean edge length"},
      {.name = "vdb-fog",
       .kind = K::Flag,
       .help = "also write a fog volume (density) per body",
       .commands = kOptionRun,
       .recorded = true},
      {.name = "vdb-compression",
       .kind = K::Choice,
       .help = "VDB file compression: zip (the default), blosc or none",
       .commands = kOptionRun,
       .choices = vdbCompressions,
       .recorded = true},
      {.name = "up",
       .kind = K::Choice,
       .help = "up axis of the VDB export and the point caches: y (Houdini) or z (Blender)",
       .commands = kOptionRun,
       .choices = upAxes,
       .recorded = true},

      // How the run goes: nothing here changes a file.
      {.name = "threads",
       .shortFlag = "-j",
       .kind = K::Whole,
       .help = "worker threads (0: all cores)",
       .commands = kSimulate,
       .low = 0,
       .high = 4096},
      {.name = "quiet",
       .shortFlag = "-q",
       .kind = K::Flag,
       .help = "print errors and the final summary only",
       .commands = kOptionRun},
      {.name = "max-output-gib",
       .kind = K::Number,
       .help = "refuse, before any work, a run whose frames would take more than this many GiB "
               "on disk (estimated)",
       .commands = kOptionRun,
       .low = 0,
       .high = HUGE_VAL,
       .aboveLow = true,
       .defaultText = "1024"},
      {.name = "no-cache",
       .kind = K::Flag,
       .help = "write no simulation cache (OUT/cache): the run cannot be resumed or exported "
               "from",
       .commands = kOptionRun},
      {.name = "checkpoint-every",
       .kind = K::Whole,
       .help = "frames between the cache's checkpoints (default: as many as keep them within a "
               "tenth of the cache)",
       .commands = kOptionRun,
       .low = 1,
       .high = 10'000'000,
       .excludes = "no-cache"},
      {.name = "cache-only",
       .kind = K::Flag,
       .help = "write the simulation cache alone; `export --all` writes the outputs later (how "
               "`farm` splits a bake)",
       .commands = kOptionRun,
       .excludes = "no-cache",
       .recorded = true},
      {.name = "resume",
       .kind = K::Flag,
       .help = "continue the killed, interrupted or failed run in OUT from its last checkpoint, "
               "writing only the missing files; the same command and files, or an error that "
               "says what changed",
       .commands = kOptionRun},
      {.name = "report",
       .kind = K::Path,
       .help = "write a bake report into this folder: DIR/index.html, every frame's substeps, "
               "contacts, energy, volumes and step time plotted, the frames that look wrong, a "
               "flipbook of the PNG frames; also when the run fails",
       .commands = kOptionRun},
  };
}
#pragma GCC diagnostic pop

/// `number` as a command line writes it: the shortest decimal that reads back the same.
std::string numberText(double number) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, number).ptr);
}

/// An integer of the JSON value, if it is one (2.0 counts; 2.5 and true do not).
std::optional<long long> integerOf(const nlohmann::json& value) {
  if (value.is_number_integer()) return value.get<long long>();
  if (value.is_number_float()) {
    const double x = value.get<double>();
    if (std::isfinite(x) && x == std::floor(x) && std::fabs(x) < 0x1p63) return (long long)x;
  }
  return std::nullopt;
}

std::string wholeRange(const OptionSpec& spec) {
  return cat("a whole number from ", (long long)spec.low, " to ", (long long)spec.high);
}

std::optional<OptionValueError> wrongType(std::string message) {
  return OptionValueError{true, std::move(message)};
}
std::optional<OptionValueError> outOfRange(std::string message) {
  return OptionValueError{false, std::move(message)};
}

std::optional<OptionValueError> checkWhole(const OptionSpec& spec, const nlohmann::json& value,
                                           const std::string& expected) {
  // 2.5 is no count; 1e30 is one, out of range.
  if (!value.is_number() || value.is_boolean() ||
      (value.is_number_float() && !(value.get<double>() == std::floor(value.get<double>()))))
    return wrongType("expected " + expected);
  const std::optional<long long> x = integerOf(value);
  if (!x || double(*x) < spec.low || double(*x) > spec.high)
    return outOfRange("expected " + expected);
  return std::nullopt;
}

}  // namespace

std::string OptionSpec::keyword() const {
  std::string word(name);
  for (char& c : word)
    if (c == '-') c = '_';
  return word;
}

const std::vector<OptionSpec>& optionTable() {
  static const std::vector<OptionSpec> table = makeTable();
  return table;
}

const OptionSpec& optionSpec(std::string_view name) {
  for (const OptionSpec& spec : optionTable())
    if (spec.name == name) return spec;
  throw std::logic_error(cat("no option '", name, "' in the option table"));
}

bool isNegation(const OptionSpec& spec) {
  return !spec.excludes.empty() && spec.name == cat("no-", spec.excludes);
}

const OptionSpec* negationOf(const OptionSpec& spec) {
  for (const OptionSpec& other : optionTable())
    if (other.excludes == spec.name && isNegation(other)) return &other;
  return nullptr;
}

nlohmann::json::json_pointer sceneKeyPointer(const OptionSpec& spec) {
  std::string path(spec.sceneKey);
  std::replace(path.begin(), path.end(), '.', '/');
  path.insert(path.begin(), '/');
  return nlohmann::json::json_pointer(path);
}

std::optional<OptionValueError> checkOptionValue(const OptionSpec& spec,
                                                 const nlohmann::json& value, char quote) {
  switch (spec.kind) {
    case OptionKind::Flag:
      if (!value.is_boolean()) return wrongType("expected true or false");
      return std::nullopt;
    case OptionKind::Whole:
      return checkWhole(spec, value, wholeRange(spec));
    case OptionKind::Number: {
      if (!value.is_number() || value.is_boolean()) return wrongType("expected a number");
      const double x = value.get<double>();
      const bool low = spec.aboveLow ? x > spec.low : x >= spec.low;
      if (std::isfinite(x) && low && x <= spec.high) return std::nullopt;
      if (!spec.aboveLow)
        return outOfRange(
            cat("expected a number from ", numberText(spec.low), " to ", numberText(spec.high)));
      if (std::isinf(spec.high)) return outOfRange(cat("expected a number above ", spec.low));
      return outOfRange(cat("expected a number above ", numberText(spec.low), " and at most ",
                            numberText(spec.high)));
    }
    case OptionKind::Choice: {
      const std::vector<std::string> names = spec.choices();
      const std::string expected = cat("expected ", alternatives(names, std::string(1, quote)));
      if (!value.is_string()) return wrongType(expected);
      for (const std::string& name : names)
        if (value.get<std::string>() == name) return std::nullopt;
      return outOfRange(expected);
    }
    case OptionKind::Substeps: {
      const std::string expected = cat(quote, "auto", quote, " or ", wholeRange(spec));
      if (value.is_string()) {
        if (value.get<std::string>() == "auto") return std::nullopt;
        return outOfRange("expected " + expected);
      }
      return checkWhole(spec, value, expected);
    }
    case OptionKind::ImageSize: {
      const std::string expected =
          cat("[width, height], each ", wholeRange(spec), " (WIDTHxHEIGHT on a command line)");
      if (!value.is_array() || value.size() != 2) return wrongType("expected " + expected);
      for (const nlohmann::json& side : value)
        if (auto error = checkWhole(spec, side, expected)) return error;
      return std::nullopt;
    }
    case OptionKind::Path:
      if (!value.is_string()) return wrongType("expected a path");
      if (value.get<std::string>().empty()) return outOfRange("expected a path");
      return std::nullopt;
  }
  return std::nullopt;
}

nlohmann::json optionValueFromText(const OptionSpec& spec, std::string_view text) {
  const auto whole = [](std::string_view t) -> std::optional<long long> {
    long long x = 0;
    const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), x);
    if (error != std::errc() || end != t.data() + t.size()) return std::nullopt;
    return x;
  };
  switch (spec.kind) {
    case OptionKind::Flag:
      if (text == "true") return true;
      if (text == "false") return false;
      break;
    case OptionKind::Whole:
    case OptionKind::Substeps:
      if (auto x = whole(text)) return *x;
      break;
    case OptionKind::Number: {
      double x = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), x);
      if (error == std::errc() && end == text.data() + text.size()) return x;
      break;
    }
    case OptionKind::ImageSize: {
      const std::size_t x = text.find_first_of("xX");
      if (x == std::string_view::npos) break;
      const auto width = whole(text.substr(0, x)), height = whole(text.substr(x + 1));
      if (width && height) return nlohmann::json::array({*width, *height});
      break;
    }
    case OptionKind::Choice:
    case OptionKind::Path:
      break;
  }
  return std::string(text);
}

std::vector<std::string> optionWords(const OptionSpec& spec, const nlohmann::json& value) {
  if (spec.kind == OptionKind::Flag) return {spec.flag()};
  if (spec.kind == OptionKind::ImageSize)
    return {spec.flag(), cat(value[0].get<long long>(), "x", value[1].get<long long>())};
  if (value.is_string()) return {spec.flag(), value.get<std::string>()};
  if (value.is_number_float()) return {spec.flag(), numberText(value.get<double>())};
  return {spec.flag(), value.dump()};
}

void giveOption(GivenOptions& given, const OptionSpec& spec, const nlohmann::json& value) {
  if (auto error = checkOptionValue(spec, value))
    throw Error(cat(spec.flag(), ": ", error->message, ", got ", value.dump()));
  given[std::string(spec.name)] = value;
}

void applySceneOptions(const GivenOptions& given, SceneFile& scene) {
  nlohmann::json document = nlohmann::json::object();
  for (const OptionSpec& spec : optionTable()) {
    const auto found = given.find(std::string(spec.name));
    if (spec.sceneKey.empty() || found == given.end()) continue;
    if (spec.kind == OptionKind::Flag && !found->get<bool>()) continue;  // not given
    document[sceneKeyPointer(spec)] = spec.kind == OptionKind::Flag ? spec.value : *found;
  }
  if (!document.empty()) applySceneKeys(scene, document, "the options");
}

void applyLoadOptions(const GivenOptions& given, SceneLoadOptions& load) {
  for (const OptionSpec& spec : optionTable()) {
    const auto found = given.find(std::string(spec.name));
    if (found == given.end()) continue;
    std::visit(
        [&](auto field) {
          using Field = decltype(field);
          if constexpr (std::is_same_v<Field, bool SceneLoadOptions::*>)
            load.*field = found->get<bool>();
          else if constexpr (std::is_same_v<Field,
                                            std::optional<std::uint64_t> SceneLoadOptions::*>)
            load.*field = found->get<std::uint64_t>();
          else if constexpr (std::is_same_v<Field, std::size_t SceneLoadOptions::*>)
            load.*field = found->get<std::size_t>();
        },
        spec.load);
  }
}

}  // namespace softbake
