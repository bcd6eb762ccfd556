#include "cli/wedge.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <map>
#include <thread>

#include "bake/command_errors.hpp"
#include "cli/scene_command.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/scene_file.hpp"
#include "output/atomic_file.hpp"

extern char** environ;

namespace softbake {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// "a,[1,2],\"x,y\"" → "a", "[1,2]", "\"x,y\"": commas inside brackets, braces or quotes stay.
std::vector<std::string> splitValues(const std::string& text) {
  std::vector<std::string> values(1);
  int depth = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '\\' && i + 1 < text.size())
        values.back() += text[i++];
      else if (c == '"')
        quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      --depth;
    } else if (c == ',' && depth == 0) {
      values.emplace_back();
      continue;
    }
    values.back() += c;
  }
  return values;
}

/// One step of a key path: a key, or an index when `key` is empty.
struct PathStep {
  std::string key;
  std::size_t index = 0;
};

std::vector<PathStep> parsePath(const std::string& path) {
  std::vector<PathStep> steps;
  std::size_t i = 0;
  while (i < path.size()) {
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      const std::string digits = path.substr(i + 1, close == std::string::npos ? 0 : close - i - 1);
      if (close == std::string::npos || digits.empty() ||
          digits.find_first_not_of("0123456789") != std::string::npos)
        throw Error(cat("--vary ", path, ": expected [index] at character ", i + 1));
      steps.push_back({"", std::stoul(digits)});
      i = close + 1;
      if (i < path.size() && path[i] == '.') ++i;
    } else {
      const std::size_t end = path.find_first_of(".[", i);
      const std::string key = path.substr(i, end == std::string::npos ? end : end - i);
      if (key.empty()) throw Error(cat("--vary ", path, ": an empty key at character ", i + 1));
      steps.push_back({key, 0});
      i = end == std::string::npos ? path.size() : end + (path[end] == '.' ? 1 : 0);
    }
  }
  if (steps.empty()) throw Error("--vary: an empty key path");
  return steps;
}

/// Sets `path` in `scene` to `value`. Every step but the last must exist; the last may be a new
/// key of an object (a setting the scene leaves to its default).
void setPath(Json& scene, const std::string& path, const Json& value) {
  const std::vector<PathStep> steps = parsePath(path);
  Json* node = &scene;
  std::string walked;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (!step.key.empty()) {
      if (!node->is_object())
        throw Error(cat("--vary ", path, ": ", walked.empty() ? "the scene" : walked,
                        " is not an object (it is ", node->dump(), ")"));
      if (!last && !node->contains(step.key))
        throw Error(cat("--vary ", path, ": the scene has no ", walked, walked.empty() ? "" : ".",
                        step.key));
      walked += (walked.empty() ? "" : ".") + step.key;
      node = &(*node)[step.key];
    } else {
      if (!node->is_array() || step.index >= node->size())
        throw Error(cat("--vary ", path, ": the scene has no ", walked, "[", step.index, "]"));
      walked += cat("[", step.index, "]");
      node = &(*node)[step.index];
    }
  }
  *node = value;
}

/// Mesh paths of bodies and mesh colliders, made absolute against `directory`.
void absoluteMeshPaths(Json& scene, const fs::path& directory) {
  for (const char* list : {"bodies", "colliders"}) {
    if (!scene.contains(list) || !scene[list].is_array()) continue;
    for (Json& item : scene[list])
      if (item.is_object() && item.contains("mesh") && item["mesh"].is_string()) {
        const fs::path mesh = item["mesh"].get<std::string>();
        if (mesh.is_relative()) item["mesh"] = fs::absolute(directory / mesh).lexically_normal();
      }
  }
}

/// A value as a table shows it: strings bare, everything else as JSON.
std::string shown(const Json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

/// The `softbake` binary this process runs from, to start the variants' runs.
std::string selfPath() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (error) throw Error(cat("cannot find the softbake binary: /proc/self/exe: ", error.message()));
  return self.string();
}

/// Starts `softbake ARGUMENTS`, its output to `log`.
pid_t start(const std::string& binary, const std::vector<std::string>& arguments,
            const fs::path& log) {
  std::vector<std::string> words{binary};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  const int failed = posix_spawn(&pid, binary.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (failed != 0) throw Error(cat("cannot start ", binary, ": ", std::strerror(failed)));
  return pid;
}

}  // namespace

WedgeVariation parseVariation(const std::string& text) {
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos || equals == 0 || equals + 1 == text.size())
    throw Error(cat("--vary '", text, "': expected KEY.PATH=VALUE1,VALUE2,…"));
  WedgeVariation variation;
  variation.path = text.substr(0, equals);
  parsePath(variation.path);  // reports a malformed path now
  for (const std::string& value : splitValues(text.substr(equals + 1))) {
    if (value.empty()) throw Error(cat("--vary '", text, "': an empty value"));
    Json parsed = Json::parse(value, nullptr, /*allow_exceptions=*/false);
    variation.values.push_back(parsed.is_discarded() ? Json(value) : std::move(parsed));
  }
  return variation;
}

std::vector<WedgeVariant> expandWedge(const Json& scene, const fs::path& sceneDirectory,
                                      const std::vector<WedgeVariation>& variations) {
  std::size_t count = 1;
  for (const WedgeVariation& variation : variations) count *= variation.values.size();
  if (count > 100000) throw Error(cat("--vary: ", count, " variants is more than 100000"));
  const int digits = std::max<int>(3, int(std::to_string(count - 1).size()));
  std::vector<WedgeVariant> variants;
  for (std::size_t v = 0; v < count; ++v) {
    WedgeVariant variant;
    std::string number = std::to_string(v);
    number.insert(0, std::size_t(digits) - number.size(), '0');
    variant.name = cat("wedge_", number);
    variant.scene = scene;
    absoluteMeshPaths(variant.scene, sceneDirectory);
    // Mixed radix, the last variation fastest.
    std::size_t rest = v;
    std::vector<std::size_t> choice(variations.size());
    for (std::size_t k = variations.size(); k-- > 0;) {
      choice[k] = rest % variations[k].values.size();
      rest /= variations[k].values.size();
    }
    for (std::size_t k = 0; k < variations.size(); ++k) {
      const Json& value = variations[k].values[choice[k]];
      setPath(variant.scene, variations[k].path, value);
      variant.values.push_back(value);
    }
    variants.push_back(std::move(variant));
  }
  return variants;
}

std::vector<PreparedVariant> prepareWedge(const std::string& input,
                                          const std::vector<WedgeVariation>& variations,
                                          const fs::path& out) {
  const Json scene = resolveSceneJson(input);
  std::error_code error;
  const fs::path directory =
      fs::is_regular_file(input, error) ? fs::path(input).parent_path() : fs::current_path();
  const std::vector<WedgeVariant> variants = expandWedge(scene, directory, variations);
  // Every variant is checked before any is written: a value out of range names its variant.
  for (const WedgeVariant& variant : variants) {
    try {
      parseScene(variant.scene, variant.name + "/scene.json", fs::current_path());
    } catch (const Error& failure) {
      std::string what;
      for (std::size_t k = 0; k < variations.size(); ++k)
        what += cat(k ? ", " : "", variations[k].path, "=", shown(variant.values[k]));
      throw Error(cat("wedge variant ", variant.name, " (", what, "): ", failure.what()));
    }
  }
  makeDirectories(out);
  std::vector<PreparedVariant> prepared;
  std::string csv = "variant", markdown = "| variant |", rule = "|---|";
  for (const WedgeVariation& variation : variations) {
    csv += cat(",", csvField(variation.path));
    markdown += cat(" `", variation.path, "` |");
    rule += "---|";
  }
  csv += "\n";
  markdown += cat("\n", rule, "\n");
  for (const WedgeVariant& variant : variants) {
    const fs::path folder = out / variant.name;
    makeDirectories(folder);
    writeFileAtomically(folder / "scene.json", variant.scene.dump(2) + "\n");
    prepared.push_back({variant.name, folder, folder / "scene.json"});
    csv += variant.name;
    markdown += cat("| ", variant.name, " |");
    for (const Json& value : variant.values) {
      csv += cat(",", csvField(shown(value)));
      markdown += cat(" ", shown(value), " |");
    }
    csv += "\n";
    markdown += "\n";
  }
  writeFileAtomically(out / "wedge.csv", csv);
  writeFileAtomically(out / "wedge.md", markdown);
  return prepared;
}

int wedgeCommand(const WedgeOptions& options) {
  return reportingErrors([&] {
    std::vector<WedgeVariation> variations;
    for (const std::string& text : options.vary) variations.push_back(parseVariation(text));
    const std::vector<PreparedVariant> variants =
        prepareWedge(options.input, variations, options.out);
    std::printf("wedge: %zu variants in %s (table: %s)\n", variants.size(),
                options.out.string().c_str(), (options.out / "wedge.md").string().c_str());
    if (!options.bake) return 0;

    // Variants are independent: as many at once as there are cores, the cores shared out among
    // them (a run's results do not depend on its thread count).
    const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
    const int parallel =
        std::min<int>(options.parallel > 0 ? options.parallel : cores, int(variants.size()));
    const int threads = std::max(1, cores / std::max(1, parallel));
    const std::string binary = selfPath();
    std::map<pid_t, std::size_t> running;
    std::vector<std::string> failures;
    std::size_t next = 0;
    while (next < variants.size() || !running.empty()) {
      while (next < variants.size() && int(running.size()) < parallel) {
        const PreparedVariant& variant = variants[next];
        std::vector<std::string> arguments{
            "run", variant.scene.string(),  "-o", variant.folder.string(),
            "-j",  std::to_string(threads), "-q"};
        arguments.insert(arguments.end(), options.runArguments.begin(), options.runArguments.end());
        running[start(binary, arguments, variant.folder / "run.log")] = next++;
      }
      int status = 0;
      const pid_t done = ::wait(&status);
      if (done < 0) {
        if (errno == EINTR) continue;
        break;
      }
      const auto found = running.find(done);
      if (found == running.end()) continue;
      const PreparedVariant& variant = variants[found->second];
      running.erase(found);
      const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
      std::printf("%s %s\n", variant.name.c_str(), ok ? "baked" : "FAILED");
      if (!ok)
        failures.push_back(cat(variant.name, ": see ", (variant.folder / "run.log").string()));
      std::fflush(stdout);
    }
    if (failures.empty()) {
      std::printf("wedge: all %zu variants baked, %d at a time\n", variants.size(), parallel);
      return 0;
    }
    std::string list;
    for (const std::string& failure : failures) list += cat("\n  ", failure);
    throw Error(cat(failures.size(), " of ", variants.size(), " variants failed:", list));
  });
}

}  // namespace softbake
