#include "cli/bake_comparison.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <set>

#include "cli/bake_sequence.hpp"
#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string names(const std::vector<BakeBody>& bodies) {
  std::string text;
  for (const BakeBody& body : bodies) text += cat(text.empty() ? "'" : ", '", body.name, "'");
  return text;
}

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g%%", 100 * fraction);
  return text;
}

/// The enclosed volume by the divergence theorem: a sum of signed tetrahedra from the origin.
double volumeOf(const BakeBody& body, const std::vector<Vec3f>& positions) {
  double volume = 0;
  for (const auto& t : body.triangles) {
    const Eigen::Vector3d a = positions[body.firstParticle + t[0]].cast<double>(),
                          b = positions[body.firstParticle + t[1]].cast<double>(),
                          c = positions[body.firstParticle + t[2]].cast<double>();
    volume += a.dot(b.cross(c)) / 6;
  }
  return volume;
}

double sizeOf(const BakeBody& body, const std::vector<Vec3f>& positions) {
  Eigen::AlignedBox3f box;
  for (std::size_t i = 0; i < body.particles; ++i) box.extend(positions[body.firstParticle + i]);
  return box.isEmpty() ? 0 : double(box.sizes().maxCoeff());
}

/// One body in one frame.
struct BodyMeasure {
  double maxDistance = 0, rmsDistance = 0;  ///< fractions of the body's size
  double volumeChange = kNaN;               ///< fraction of A's volume; NaN when not known
  long contactsA = -1, contactsB = -1;      ///< -1 when not known
};

/// Which threshold `m` exceeds most, as "max distance 0.13% of its size > 0.1%", and by how
/// much (the measure over its threshold); empty and the largest ratio when none is exceeded.
std::pair<std::string, double> worstExcess(const BodyMeasure& m, const BakeThresholds& t) {
  std::string what;
  double worst = 0;
  const auto consider = [&](double value, double limit, const std::string& text) {
    const double ratio = limit > 0 ? value / limit : (value > 0 ? 1e300 : 0);
    if (value > limit && ratio > worst) what = text;
    worst = std::max(worst, ratio);
  };
  consider(m.maxDistance, t.maxDistance,
           cat("max distance ", percent(m.maxDistance), " of its size > ", percent(t.maxDistance)));
  consider(m.rmsDistance, t.maxRms,
           cat("RMS distance ", percent(m.rmsDistance), " of its size > ", percent(t.maxRms)));
  if (std::isfinite(m.volumeChange))
    consider(std::abs(m.volumeChange), t.maxVolumeChange,
             cat("volume change ", percent(m.volumeChange), " > ", percent(t.maxVolumeChange)));
  if (m.contactsA >= 0 && m.contactsB >= 0) {
    const double change =
        double(std::abs(m.contactsB - m.contactsA)) / double(std::max(m.contactsA, 1L));
    consider(change, t.maxContactChange,
             cat("contacts ", m.contactsA, " then ", m.contactsB, ", a change of ", percent(change),
                 " > ", percent(t.maxContactChange)));
  }
  return {what, worst};
}

std::string describe(const std::string& body, const BodyMeasure& m) {
  std::string text = cat(body, ": max distance ", percent(m.maxDistance), " of its size, RMS ",
                         percent(m.rmsDistance));
  if (std::isfinite(m.volumeChange))
    text += cat(", volume ", m.volumeChange >= 0 ? "+" : "", percent(m.volumeChange));
  if (m.contactsA >= 0 && m.contactsB >= 0)
    text += cat(", contacts ", m.contactsA,
                m.contactsA == m.contactsB ? "" : cat(" then ", m.contactsB));
  return text;
}

}  // namespace

Comparison compareBakes(const std::filesystem::path& reference,
                        const std::filesystem::path& candidate, const BakeThresholds& thresholds) {
  const BakeSequence a = BakeSequence::open(reference), b = BakeSequence::open(candidate);
  std::vector<std::string> namesA, namesB;
  for (const BakeBody& body : a.bodies()) namesA.push_back(body.name);
  for (const BakeBody& body : b.bodies()) namesB.push_back(body.name);
  if (namesA != namesB)
    throw Error(cat("these are bakes of different scenes: ", a.description(), " has the bodies ",
                    names(a.bodies()), "; ", b.description(), " has ", names(b.bodies())));

  Comparison comparison;
  comparison.kind = "bakes";
  comparison.reference = reference.string();
  comparison.candidate = candidate.string();
  comparison.thresholds = cat("per body and frame: max distance ", percent(thresholds.maxDistance),
                              " of the body's size, RMS distance ", percent(thresholds.maxRms),
                              ", volume change ", percent(thresholds.maxVolumeChange),
                              ", contact change ", percent(thresholds.maxContactChange));
  comparison.notes = {cat("reference: ", a.description()), cat("new: ", b.description())};
  for (const BakeSequence* bake : {&a, &b})
    comparison.notes.insert(comparison.notes.end(), bake->notes().begin(), bake->notes().end());

  // Topology: a body whose particles or triangles differ is not compared further.
  const std::size_t bodies = a.bodies().size();
  std::vector<bool> sameTopology(bodies, true);
  std::vector<bool> volumes(bodies, false);
  for (std::size_t i = 0; i < bodies; ++i) {
    const BakeBody &x = a.bodies()[i], &y = b.bodies()[i];
    const bool known = !x.triangles.empty() && !y.triangles.empty();
    if (x.particles != y.particles || x.triangleCount != y.triangleCount ||
        (known && x.triangles != y.triangles)) {
      sameTopology[i] = false;
      ComparedItem& item = comparison.items.emplace_back();
      item.name = cat("topology of ", x.name);
      item.verdict = Verdict::Fail;
      item.summary = cat(
          "the body's topology changed: ", x.particles, " particles and ", x.triangleCount,
          " triangles, then ", y.particles, " and ", y.triangleCount,
          x.particles == y.particles && x.triangleCount == y.triangleCount ? " with other triangles"
                                                                           : "");
      item.severity = 1e300;
    }
    volumes[i] = known && sameTopology[i];
  }

  const std::vector<int> framesA = a.frames(), framesB = b.frames();
  std::set<int> all(framesA.begin(), framesA.end());
  all.insert(framesB.begin(), framesB.end());
  const std::set<int> inA(framesA.begin(), framesA.end()), inB(framesB.begin(), framesB.end());

  Plot distance{"largest particle distance", "% of the body's size", {}, namesA, {}, {}, {}};
  Plot volume{"volume change", "% of the reference's", {}, namesA, {}, {}, {}};
  Plot contacts{"contacts", "count", {}, {"reference", "new"}, {{}, {}}, {}, {}};
  distance.series.resize(bodies);
  volume.series.resize(bodies);
  std::vector<double> sizes;
  std::vector<std::optional<std::string>> firstOver(bodies);
  for (const int frame : all) {
    ComparedItem item;
    item.name = cat("frame ", frame);
    for (Plot* plot : {&distance, &volume, &contacts}) plot->frames.push_back(frame);
    if (!inA.count(frame) || !inB.count(frame)) {
      item.verdict = Verdict::Fail;
      item.summary =
          inA.count(frame)
              ? cat("frame ", frame, " is missing in the new bake (", candidate.string(), ")")
              : cat("frame ", frame, " is not in the reference bake (", reference.string(), ")");
      item.severity = 1e300;
      item.missing = true;
      for (Plot* plot : {&distance, &volume, &contacts})
        for (auto& series : plot->series) series.push_back(kNaN);
      comparison.items.push_back(std::move(item));
      continue;
    }
    const BakeFrame x = a.read(frame), y = b.read(frame);
    if (sizes.empty())
      for (const BakeBody& body : a.bodies()) sizes.push_back(sizeOf(body, x.positions));
    std::string worstText;
    double worstRatio = -1;
    long totalA = 0, totalB = 0;
    for (std::size_t i = 0; i < bodies; ++i) {
      const BakeBody& body = a.bodies()[i];
      if (!sameTopology[i]) {
        distance.series[i].push_back(kNaN);
        volume.series[i].push_back(kNaN);
        item.details.push_back(cat(body.name, ": not compared, its topology changed"));
        continue;
      }
      BodyMeasure m;
      const double size = std::max(sizes[i], 1e-12);
      double squared = 0;
      for (std::size_t p = body.firstParticle; p < body.firstParticle + body.particles; ++p) {
        const double d = double((x.positions[p] - y.positions[p]).norm());
        m.maxDistance = std::max(m.maxDistance, d / size);
        squared += d * d;
      }
      m.rmsDistance = body.particles ? std::sqrt(squared / double(body.particles)) / size : 0;
      if (volumes[i]) {
        const double va = volumeOf(body, x.positions), vb = volumeOf(body, y.positions);
        // An open surface encloses nothing to compare.
        if (std::abs(va) > 1e-9 * size * size * size) m.volumeChange = (vb - va) / std::abs(va);
      }
      if (!x.contacts.empty() && !y.contacts.empty()) {
        m.contactsA = long(x.contacts[i]);
        m.contactsB = long(y.contacts[i]);
        totalA += m.contactsA;
        totalB += m.contactsB;
      }
      distance.series[i].push_back(100 * m.maxDistance);
      volume.series[i].push_back(100 * m.volumeChange);
      const auto [excess, ratio] = worstExcess(m, thresholds);
      const std::string line = describe(body.name, m);
      item.details.push_back(line);
      if (!excess.empty()) {
        item.verdict = Verdict::Fail;
        if (!firstOver[i])
          firstOver[i] = cat(body.name, ": first over a threshold at frame ", frame, ": ", excess);
      } else if (item.verdict == Verdict::Pass &&
                 (m.maxDistance > 0 || m.contactsA != m.contactsB ||
                  (std::isfinite(m.volumeChange) && m.volumeChange != 0))) {
        item.verdict = Verdict::Warn;  // changed, within the thresholds
      }
      if (ratio > worstRatio) worstRatio = ratio, worstText = line;
    }
    const bool contactsKnown = !x.contacts.empty() && !y.contacts.empty();
    contacts.series[0].push_back(contactsKnown ? double(totalA) : kNaN);
    contacts.series[1].push_back(contactsKnown ? double(totalB) : kNaN);
    item.severity = std::max(0.0, worstRatio);
    item.summary = worstText.empty()               ? "no body compared"
                   : item.verdict == Verdict::Pass ? "identical in every body"
                                                   : cat("most changed: ", worstText);
    comparison.items.push_back(std::move(item));
  }
  for (const std::optional<std::string>& line : firstOver)
    if (line) comparison.notes.push_back(*line);
  comparison.plots = {distance, volume};
  if (a.hasContacts() && b.hasContacts()) comparison.plots.push_back(contacts);
  return comparison;
}

}  // namespace softbake
