#include "output/manifest.hpp"

#include <fstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"

#include "core/text.hpp"
#include "output/atomic_file.hpp"
#include "output/finite_values.hpp"
#include "output/version.hpp"

namespace softbake {

Manifest describeScene(const SceneTopology& topology, std::string scene, int framesWritten,
                       int framePadding) {
  Manifest manifest;
  manifest.scene = std::move(scene);
  manifest.fps = topology.settings.fps;
  manifest.framesWritten = framesWritten;
  manifest.framePadding = framePadding;
  manifest.units = topology.settings.units;
  for (const Body& body : topology.bodies)
    manifest.bodies.push_back({body.name, body.particleCount, body.triangleCount, body.closed,
                               body.closed && body.gasAmount != 0});
  return manifest;
}

std::string sequenceFilePath(const OutputSequence& sequence, int padding, int frame) {
  // The pattern's last run of `padding` '#' is the number; a '#' in the scene name stays.
  const std::size_t last = sequence.pattern.rfind('#');
  if (last == std::string::npos || last + 1 < std::size_t(padding))
    throw Error(cat("the sequence pattern '", sequence.pattern, "' has no frame number"));
  std::string digits = std::to_string(frame);
  if (digits.size() < std::size_t(padding))
    digits.insert(0, std::size_t(padding) - digits.size(), '0');
  return sequence.pattern.substr(0, last + 1 - std::size_t(padding)) + digits +
         sequence.pattern.substr(last + 1);
}

std::string_view runStatusName(RunStatus status) {
  switch (status) {
    case RunStatus::Complete:
      return "complete";
    case RunStatus::Incomplete:
      return "incomplete";
    case RunStatus::Failed:
      return "failed";
  }
  return "failed";
}

std::string manifestJson(const Manifest& manifest) {
  // ordered_json keeps the keys in the order written here: the file reads top-down.
  using Json = nlohmann::ordered_json;
  Json bodies = Json::array();
  for (const ManifestBody& body : manifest.bodies)
    bodies.push_back({{"name", body.name},
                      {"particles", body.particles},
                      {"triangles", body.triangles},
                      {"closed", body.closed},
                      {"pressure", body.pressure}});
  Json pointCaches = Json::array();
  for (const ManifestPointCache& cache : manifest.pointCaches) {
    Json entry = {{"body", cache.body}, {"mesh", cache.restMesh}, {"up", manifest.pointCacheUp}};
    entry["pc2"] = cache.pc2.empty() ? Json(nullptr) : Json(cache.pc2);
    entry["mdd"] = cache.mdd.empty() ? Json(nullptr) : Json(cache.mdd);
    pointCaches.push_back(std::move(entry));
  }
  Json sequences = Json::array();
  for (const OutputSequence& sequence : manifest.sequences)
    sequences.push_back({{"format", sequence.format},
                         {"pattern", sequence.pattern},
                         {"printf_pattern", sequence.printfPattern},
                         {"files", sequence.files}});
  Json json = {{"scene", manifest.scene}, {"status", runStatusName(manifest.status)}};
  if (!manifest.reason.empty()) json["reason"] = manifest.reason;
  json.update(Json{{"frames_complete", manifest.framesComplete},
                   {"softbake_version", softbakeVersion()},
                   {"fps", manifest.fps},
                   {"frames", manifest.framesWritten},
                   {"first_frame", manifest.firstFrame},
                   {"frame_padding", manifest.framePadding},
                   {"units", manifest.units},
                   {"bodies", std::move(bodies)},
                   {"sequences", std::move(sequences)},
                   {"point_caches", std::move(pointCaches)}});
  if (!manifest.setAsidePairs.empty()) json["set_aside_pairs"] = manifest.setAsidePairs;
  json["run"] = manifest.run;
  // Names come from user files; invalid UTF-8 is replaced rather than failing the whole run.
  return json.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

Manifest readManifest(const std::filesystem::path& outputDirectory) {
  const std::filesystem::path path = outputDirectory / "manifest.json";
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error(
        cat(path.string(), ": cannot read the manifest (is this a softbake output folder?)"));
  nlohmann::ordered_json json;
  try {
    json = nlohmann::ordered_json::parse(in);
  } catch (const nlohmann::json::exception& error) {
    throw Error(cat(path.string(), ": not valid JSON: ", error.what()));
  }
  const auto field = [&](const char* key) -> const nlohmann::ordered_json& {
    if (!json.is_object() || !json.contains(key))
      throw Error(cat(path.string(), ": '", key, "' is missing"));
    return json[key];
  };
  Manifest manifest;
  try {
    manifest.scene = field("scene").get<std::string>();
    const std::string status = field("status").get<std::string>();
    if (status == "complete")
      manifest.status = RunStatus::Complete;
    else if (status == "incomplete")
      manifest.status = RunStatus::Incomplete;
    else if (status == "failed")
      manifest.status = RunStatus::Failed;
    else
      throw Error(cat(path.string(), ": 'status' is '", status, "'"));
    if (json.contains("reason")) manifest.reason = json["reason"].get<std::string>();
    manifest.framesComplete = field("frames_complete").get<int>();
    manifest.fps = field("fps").get<double>();
    manifest.framesWritten = field("frames").get<int>();
    manifest.firstFrame = field("first_frame").get<int>();
    manifest.framePadding = field("frame_padding").get<int>();
    manifest.units = field("units").get<std::string>();
    for (const auto& body : field("bodies"))
      manifest.bodies.push_back({body.at("name").get<std::string>(),
                                 body.at("particles").get<std::size_t>(),
                                 body.at("triangles").get<std::size_t>(),
                                 body.at("closed").get<bool>(), body.at("pressure").get<bool>()});
    for (const auto& sequence : field("sequences"))
      manifest.sequences.push_back({sequence.at("format").get<std::string>(),
                                    sequence.at("pattern").get<std::string>(),
                                    sequence.at("printf_pattern").get<std::string>(),
                                    sequence.at("files").get<std::vector<std::string>>()});
    if (json.contains("point_caches"))
      for (const auto& cache : json["point_caches"]) {
        const auto text = [&](const char* key) {
          return cache.contains(key) && cache[key].is_string() ? cache[key].get<std::string>()
                                                               : std::string();
        };
        manifest.pointCaches.push_back({text("body"), text("mesh"), text("pc2"), text("mdd")});
        manifest.pointCacheUp = cache.value("up", std::string("y"));
      }
    if (json.contains("set_aside_pairs"))
      manifest.setAsidePairs = json["set_aside_pairs"].get<std::vector<std::uint64_t>>();
    manifest.run = field("run");
  } catch (const nlohmann::json::exception& error) {
    throw Error(cat(path.string(), ": ", error.what()));
  }
  return manifest;
}

void writeManifest(const std::filesystem::path& outputDirectory, const Manifest& manifest) {
  const std::filesystem::path path = outputDirectory / "manifest.json";
  // JSON has no NaN: nlohmann would write null for it.
  requireFinite(path, manifest.fps, [] { return std::string("the scene's fps"); });
  writeFileAtomically(path, manifestJson(manifest));
}

}  // namespace softbake
