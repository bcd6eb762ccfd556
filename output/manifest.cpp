#include "output/manifest.hpp"

#include <nlohmann/json.hpp>

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
  Json sequences = Json::array();
  for (const OutputSequence& sequence : manifest.sequences)
    sequences.push_back({{"format", sequence.format},
                         {"pattern", sequence.pattern},
                         {"printf_pattern", sequence.printfPattern},
                         {"files", sequence.files}});
  const Json json = {{"scene", manifest.scene},
                     {"softbake_version", softbakeVersion()},
                     {"fps", manifest.fps},
                     {"frames", manifest.framesWritten},
                     {"first_frame", manifest.firstFrame},
                     {"frame_padding", manifest.framePadding},
                     {"units", manifest.units},
                     {"bodies", std::move(bodies)},
                     {"sequences", std::move(sequences)}};
  // Names come from user files; invalid UTF-8 is replaced rather than failing the whole run.
  return json.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

void writeManifest(const std::filesystem::path& outputDirectory, const Manifest& manifest) {
  const std::filesystem::path path = outputDirectory / "manifest.json";
  // JSON has no NaN: nlohmann would write null for it.
  requireFinite(path, manifest.fps, [] { return std::string("the scene's fps"); });
  writeFileAtomically(path, manifestJson(manifest));
}

}  // namespace softbake
