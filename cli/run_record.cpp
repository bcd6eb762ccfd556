#include "cli/run_record.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/file_digest.hpp"

namespace softbake {

namespace {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

/// Calls `visit(flag, field)` for every option that shapes a run's files, named after its flag.
/// One list for writing the record and reading it back, so the two cannot drift apart.
template <class Options, class Visit>
void eachRecordedOption(Options& options, Visit&& visit) {
  visit("frames", options.frames);
  visit("fps", options.fps);
  visit("integrator", options.integrator);
  visit("substeps", options.substeps);
  visit("broadphase", options.broadPhase);
  visit("levels", options.levels);
  visit("response", options.response);
  visit("no-response", options.noResponse);
  visit("no-pair-cache", options.noPairCache);
  visit("accept-lossy-import", options.load.acceptLossyImport);
  visit("max-vertices", options.load.maxVertices);
  visit("max-faces", options.load.maxFaces);
  visit("max-import-memory", options.load.maxImportMemoryMib);
  visit("max-import-seconds", options.load.maxImportSeconds);
  visit("max-bodies", options.load.maxBodies);
  visit("frame-padding", options.framePadding);
  visit("contacts", options.contacts);
  visit("render", options.render);
  visit("size", options.size);
  visit("no-contact-spheres", options.noContactSpheres);
  visit("contacts-view", options.contactsView);
  visit("render-while-simulating", options.renderWhileSimulating);
  visit("cache-only", options.cacheOnly);
  visit("vdb", options.vdb);
  visit("pc2", options.pc2);
  visit("mdd", options.mdd);
  visit("voxel-size", options.voxelSize);
  visit("vdb-fog", options.vdbFog);
  visit("up", options.upAxis);
  visit("vdb-compression", options.vdbCompression);
}

template <class T>
Json toJson(const std::optional<T>& value) {
  return value ? Json(*value) : Json(nullptr);
}
template <class T>
Json toJson(const T& value) {
  return Json(value);
}

template <class T>
void fromJson(const Json& json, std::optional<T>& value) {
  if (json.is_null())
    value.reset();
  else
    value = json.get<T>();
}
template <class T>
void fromJson(const Json& json, T& value) {
  value = json.get<T>();
}

std::string shown(const Json& value) {
  return value.is_null() ? std::string("unset") : value.dump();
}

}  // namespace

Json runRecord(const RunOptions& options, const SceneFile& scene, int checkpointEvery) {
  // A file input is recorded by its absolute path, so `export` and `--resume` find it from any
  // folder; a built-in scene by its name.
  std::error_code error;
  const bool fileInput = !options.input.empty() && fs::is_regular_file(options.input, error);
  Json files = Json::array();
  for (const fs::path& file : scene.inputFiles)
    files.push_back(
        {{"path", fs::absolute(file).lexically_normal().string()}, {"sha256", sha256OfFile(file)}});
  Json recorded = Json::object();
  eachRecordedOption(options,
                     [&](const char* flag, const auto& field) { recorded[flag] = toJson(field); });
  recorded["checkpoint-every"] = checkpointEvery;
  return {{"input",
           fileInput ? fs::absolute(options.input).lexically_normal().string() : options.input},
          {"files", std::move(files)},
          {"options", std::move(recorded)}};
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
    eachRecordedOption(options, [&](const char* flag, auto& field) {
      if (recorded.contains(flag)) fromJson(recorded[flag], field);
    });
    const int every = recorded.value("checkpoint-every", 0);
    options.cache = every > 0;
    if (every > 0) options.checkpointEvery = every;
  } catch (const nlohmann::json::exception& error) {
    throw Error(cat(source, ": run: ", error.what()));
  }
  return options;
}

int recordedCheckpointInterval(const Json& record) {
  if (!record.contains("options")) return 0;
  return record["options"].value("checkpoint-every", 0);
}

}  // namespace softbake
