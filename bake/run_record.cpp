#include "bake/run_record.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/file_digest.hpp"

namespace softbake {

namespace {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

/// What `given` records for `spec`: its value, false for a flag not given, null for any other.
Json recorded(const GivenOptions& given, const OptionSpec& spec) {
  const auto found = given.find(std::string(spec.name));
  if (found != given.end()) return *found;
  return spec.kind == OptionKind::Flag ? Json(false) : Json(nullptr);
}

std::string shown(const Json& value) {
  return value.is_null() ? std::string("unset") : value.dump();
}

}  // namespace

Json runRecord(const RunOptions& run, const SceneFile& scene, int checkpointEvery) {
  // A file input is recorded by its absolute path, so `export` and `--resume` find it from any
  // folder; a built-in scene by its name.
  std::error_code error;
  const bool fileInput = !run.input.empty() && fs::is_regular_file(run.input, error);
  Json files = Json::array();
  for (const fs::path& file : scene.inputFiles)
    files.push_back(
        {{"path", fs::absolute(file).lexically_normal().string()}, {"sha256", sha256OfFile(file)}});
  Json options = Json::object();
  for (const OptionSpec& spec : optionTable())
    if (spec.recorded) options[std::string(spec.name)] = recorded(run.given, spec);
  options["checkpoint-every"] = checkpointEvery;
  return {{"input", fileInput ? fs::absolute(run.input).lexically_normal().string() : run.input},
          {"files", std::move(files)},
          {"options", std::move(options)}};
}

std::vector<std::string> runRecordDifferences(const Json& before, const Json& now) {
  std::vector<std::string> differences;
  const auto input = [](const Json& record) {
    const std::string text = record.value("input", std::string());
    return text.empty() ? std::string("the built-in default scene") : cat("'", text, "'");
  };
  if (before.value("input", std::string()) != now.value("input", std::string()))
    differences.push_back(cat("the input: ", input(before), " then, ", input(now), " now"));
  const Json noFiles = Json::array();
  const Json& filesBefore = before.contains("files") ? before["files"] : noFiles;
  const Json& filesNow = now.contains("files") ? now["files"] : noFiles;
  for (const Json& file : filesNow) {
    const std::string path = file.value("path", std::string());
    const auto match = std::find_if(filesBefore.begin(), filesBefore.end(), [&](const Json& old) {
      return old.value("path", std::string()) == path;
    });
    if (match == filesBefore.end())
      differences.push_back(cat("'", path, "' is read now, and was not then"));
    else if (match->value("sha256", std::string()) != file.value("sha256", std::string()))
      differences.push_back(cat("'", path, "' changed (SHA-256 ",
                                match->value("sha256", std::string()).substr(0, 12), "… then, ",
                                file.value("sha256", std::string()).substr(0, 12), "… now)"));
  }
  for (const Json& file : filesBefore) {
    const std::string path = file.value("path", std::string());
    if (std::none_of(filesNow.begin(), filesNow.end(),
                     [&](const Json& f) { return f.value("path", std::string()) == path; }))
      differences.push_back(cat("'", path, "' was read then, and is not now"));
  }
  const Json noOptions = Json::object();
  const Json& optionsBefore = before.contains("options") ? before["options"] : noOptions;
  const Json& optionsNow = now.contains("options") ? now["options"] : noOptions;
  for (const auto& [flag, value] : optionsNow.items()) {
    const Json old = optionsBefore.contains(flag) ? optionsBefore[flag] : Json(nullptr);
    if (old != value)
      differences.push_back(cat("--", flag, ": ", shown(old), " then, ", shown(value), " now"));
  }
  return differences;
}

std::string listedDifferences(const std::vector<std::string>& differences) {
  std::string list;
  for (const std::string& difference : differences) list += cat("\n  ", difference);
  return list;
}

RunOptions runOptionsFromRecord(const Json& record, const fs::path& outputDirectory,
                                std::string_view source) {
  RunOptions options;
  options.out = outputDirectory;
  try {
    options.input = record.at("input").get<std::string>();
    const Json& recorded = record.at("options");
    for (const OptionSpec& spec : optionTable()) {
      if (!spec.recorded || !recorded.contains(std::string(spec.name))) continue;
      Json value = recorded[std::string(spec.name)];
      if (value.is_null() || value == false) continue;  // not given
      // A record of an older softbake wrote some values as their command line's text ("4").
      if (value.is_string()) value = optionValueFromText(spec, value.get<std::string>());
      giveOption(options.given, spec, value);
    }
    const int every = recorded.value("checkpoint-every", 0);
    if (every > 0)
      giveOption(options.given, optionSpec("checkpoint-every"), every);
    else
      giveOption(options.given, optionSpec("no-cache"), true);
    landRunOptions(options);
  } catch (const nlohmann::json::exception& error) {
    throw Error(cat(source, ": run: ", error.what()));
  } catch (const Error& error) {
    throw Error(cat(source, ": run: ", error.what()));
  }
  return options;
}

int recordedCheckpointInterval(const Json& record) {
  if (!record.contains("options")) return 0;
  return record["options"].value("checkpoint-every", 0);
}

}  // namespace softbake
