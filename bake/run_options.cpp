#include "bake/run_options.hpp"

#include <map>
#include <stdexcept>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

using Json = nlohmann::json;
using Land = void (*)(RunOptions&, const Json&);

/// Where each option of the table that is the run's own lands: the options with neither a scene
/// key nor a loading field.
const std::map<std::string_view, Land>& runFields() {
  static const std::map<std::string_view, Land> fields = {
      {"render-while-simulating",
       [](RunOptions& o, const Json& v) { o.renderWhileSimulating = v.get<bool>(); }},
      {"voxel-size", [](RunOptions& o, const Json& v) { o.voxelSize = v.get<double>(); }},
      {"vdb-fog", [](RunOptions& o, const Json& v) { o.vdbFog = v.get<bool>(); }},
      {"vdb-compression",
       [](RunOptions& o, const Json& v) { o.vdbCompression = v.get<std::string>(); }},
      {"up", [](RunOptions& o, const Json& v) { o.upAxis = v.get<std::string>(); }},
      {"threads", [](RunOptions& o, const Json& v) { o.threads = v.get<int>(); }},
      {"quiet", [](RunOptions& o, const Json& v) { o.quiet = v.get<bool>(); }},
      {"max-output-gib", [](RunOptions& o, const Json& v) { o.maxOutputGib = v.get<double>(); }},
      {"no-cache", [](RunOptions& o, const Json& v) { o.cache = !v.get<bool>(); }},
      {"checkpoint-every", [](RunOptions& o, const Json& v) { o.checkpointEvery = v.get<int>(); }},
      {"cache-only", [](RunOptions& o, const Json& v) { o.cacheOnly = v.get<bool>(); }},
      {"resume", [](RunOptions& o, const Json& v) { o.resume = v.get<bool>(); }},
      {"report", [](RunOptions& o, const Json& v) { o.report = v.get<std::string>(); }},
  };
  return fields;
}

}  // namespace

void landRunOptions(RunOptions& options) {
  const GivenOptions& given = options.given;
  for (const OptionSpec& spec : optionTable()) {
    const auto found = given.find(std::string(spec.name));
    if (found == given.end()) continue;
    if (!spec.excludes.empty() && given.contains(std::string(spec.excludes)))
      throw Error(cat(spec.flag(), " excludes --", spec.excludes));
    if (!spec.sceneKey.empty() || spec.load.index() != 0) continue;  // the scene's, the loading's
    const auto field = runFields().find(spec.name);
    if (field == runFields().end())
      throw std::logic_error(cat("the run option ", spec.flag(), " lands in no field"));
    field->second(options, *found);
  }
  applyLoadOptions(given, options.load);
}

}  // namespace softbake
