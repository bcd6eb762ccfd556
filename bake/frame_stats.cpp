#include "bake/frame_stats.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/dynamics/energy.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace {

using Json = nlohmann::ordered_json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A number, or null where there is none (JSON has no NaN).
Json numberOrNull(double value) {
  return std::isfinite(value) ? Json(value) : Json(nullptr);
}

double numberFrom(const Json& value) {
  return value.is_null() ? kNaN : value.get<double>();
}

}  // namespace

std::string frameStatsText(const std::vector<FrameStats>& records) {
  std::string text;
  for (const FrameStats& r : records) {
    Json line;
    line["frame"] = r.frame;
    line["substeps"] = r.stepped ? Json(r.substeps) : Json(nullptr);
    line["contacts"] = r.stepped ? Json(r.contacts) : Json(nullptr);
    line["plane_contacts"] = r.stepped ? Json(r.planeContacts) : Json(nullptr);
    line["step_ms"] = r.stepped ? numberOrNull(r.stepMs) : Json(nullptr);
    line["kinetic_energy"] = numberOrNull(r.kineticEnergy);
    line["elastic_energy"] = numberOrNull(r.elasticEnergy);
    line["gravity_energy"] = numberOrNull(r.gravityEnergy);
    Json volumes = Json::array();
    for (const double v : r.volumes) volumes.push_back(numberOrNull(v));
    line["volumes"] = std::move(volumes);
    text += line.dump();
    text += '\n';
  }
  return text;
}

std::vector<FrameStats> parseFrameStats(const std::string& text, const std::string& source) {
  std::vector<FrameStats> records;
  std::istringstream lines(text);
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (line.empty()) continue;
    try {
      const Json json = Json::parse(line);
      FrameStats r;
      r.frame = json.at("frame").get<int>();
      r.stepped = !json.at("substeps").is_null();
      if (r.stepped) {
        r.substeps = json.at("substeps").get<int>();
        r.contacts = json.at("contacts").get<std::size_t>();
        r.planeContacts = json.at("plane_contacts").get<std::size_t>();
        r.stepMs = numberFrom(json.at("step_ms"));
      }
      r.kineticEnergy = numberFrom(json.at("kinetic_energy"));
      r.elasticEnergy = numberFrom(json.at("elastic_energy"));
      r.gravityEnergy = numberFrom(json.at("gravity_energy"));
      for (const Json& v : json.at("volumes")) r.volumes.push_back(numberFrom(v));
      records.push_back(std::move(r));
    } catch (const nlohmann::json::exception& error) {
      throw Error(cat(source, ": line ", number, ": ", error.what()));
    }
  }
  return records;
}

FrameStatsRecorder::FrameStatsRecorder(const SceneTopology& topology, std::filesystem::path file)
    : topology_(topology), file_(std::move(file)), volumes_(topology) {}

std::string FrameStatsRecorder::keepSaved(int lastFrame) {
  std::ifstream in(file_, std::ios::binary);
  if (!in) return {};  // the earlier invocation ran without --report: the report lists the gap
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::vector<FrameStats> saved;
  try {
    saved = parseFrameStats(text, file_.string());
  } catch (const Error& error) {
    return error.what();
  }
  records_.clear();
  for (FrameStats& r : saved)
    if (r.frame >= 1 && r.frame <= lastFrame && r.volumes.size() == topology_.bodies.size() &&
        (records_.empty() || r.frame > records_.back().frame))
      records_.push_back(std::move(r));
  return {};
}

void FrameStatsRecorder::record(const Simulator& simulator, int frame,
                                std::optional<double> stepSeconds) {
  // A frame simulated again (after a resume) replaces its earlier record.
  while (!records_.empty() && records_.back().frame >= frame) records_.pop_back();
  FrameStats r;
  r.frame = frame;
  if (stepSeconds) {
    const StepStats& stats = simulator.lastFrameStats();
    r.stepped = true;
    r.substeps = simulator.substeps().substeps;
    r.contacts = stats.contacts;
    r.planeContacts = stats.planeContacts;
    r.stepMs = *stepSeconds * 1e3;
  }
  const Energy energy = computeEnergy(topology_, simulator.state());
  r.kineticEnergy = energy.kinetic;
  r.elasticEnergy = energy.spring + energy.gas + energy.bulk;
  r.gravityEnergy = energy.gravity;
  computeVolumes(topology_, simulator.state(), volumes_);
  r.volumes.resize(topology_.bodies.size());
  for (std::size_t b = 0; b < topology_.bodies.size(); ++b)
    r.volumes[b] = topology_.bodies[b].closed ? volumes_.bodyVolume[b] : kNaN;
  records_.push_back(std::move(r));
}

bool FrameStatsRecorder::has(int frame) const {
  for (const FrameStats& r : records_)
    if (r.frame == frame) return true;
  return false;
}

void FrameStatsRecorder::save() const {
  writeFileAtomically(file_, frameStatsText(records_));
}

}  // namespace softbake
