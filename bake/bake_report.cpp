#include "bake/bake_report.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "bake/markup.hpp"
#include "bake/report_page.hpp"
#include "bake/svg_plot.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kPlottedBodies = 8;   // the charts' colours
constexpr std::size_t kListedBodies = 20;   // rows of the bodies table
constexpr std::size_t kListedFrames = 100;  // rows of the flagged frames table

constexpr const char* kStyle = R"(
h2 { font-size: 1.15em; margin: 1.2em 0 0.4em; }
table.list { border-collapse: collapse; }
table.list th, table.list td { border-top: 1px solid #ccc; padding: 0.2em 0.8em 0.2em 0;
  text-align: left; vertical-align: top; }
td.bad, tr.bad td { color: #8a0000; }
#flagged td:first-child { white-space: nowrap; }
figure.plot { margin: 0.4em 0; }
#flipbook { display: flex; flex-wrap: wrap; gap: 1em; align-items: flex-start; }
#flip-view { width: 720px; max-width: 100%; }
#flip-image { width: 100%; height: auto; image-rendering: pixelated; background: #eee; }
#flip-missing { padding: 2em; background: #eee; color: #555; }
#flip-track { position: relative; height: 10px; margin: 0 8px; }
#flip-track span { position: absolute; top: 0; width: 3px; height: 10px; margin-left: -1px;
  background: #d62728; cursor: pointer; }
#flip-track span.failed { background: #000; }
#flip-slider { width: 100%; }
#flip-numbers { max-width: 30em; }
#flip-numbers td { padding: 0.1em 0.8em 0.1em 0; vertical-align: top; }
table.summary td:first-child { white-space: nowrap; }
#flip-numbers tr.bad td { color: #8a0000; font-weight: bold; }
)";

// The flipbook: the slider (or the arrow keys, the play button, a flagged frame's link or a red
// tick above the slider) picks a frame; its image and its numbers, from the data the page holds,
// are shown. Each new image is marked as it loads, as the page's own images are.
constexpr const char* kScript = R"(
const data = JSON.parse(document.getElementById('frame-data').textContent);
const slider = document.getElementById('flip-slider');
const image = document.getElementById('flip-image');
const missing = document.getElementById('flip-missing');
const numbers = document.getElementById('flip-numbers');
const label = document.getElementById('flip-frame');
const play = document.getElementById('flip-play');
if (image) {
  image.addEventListener('load', () => mark(image, true));
  image.addEventListener('error', () => mark(image, false));
}
function text(v) {
  if (v === null || v === undefined) return '\u2013';
  const a = Math.abs(v);
  return a !== 0 && (a >= 1e5 || a < 1e-3) ? v.toExponential(3) : String(+v.toPrecision(4));
}
function show(index) {
  index = Math.max(0, Math.min(data.frames.length - 1, index));
  const f = data.frames[index];
  slider.value = index;
  label.textContent = 'frame ' + f.frame + ' (' + text((f.frame - 1) / data.fps) + ' s)';
  if (image) {
    image.hidden = !f.image;
    missing.hidden = !!f.image;
    if (f.image && image.getAttribute('src') !== f.image) {
      image.dataset.state = 'loading';
      image.src = f.image;
    }
  }
  numbers.replaceChildren();
  const row = (name, value, bad) => {
    const tr = numbers.insertRow();
    tr.insertCell().textContent = name;
    tr.insertCell().textContent = value;
    if (bad) tr.className = 'bad';
  };
  row('substeps', text(f.substeps), f.at_cap);
  row('contacts', text(f.contacts));
  row('plane contacts', text(f.plane_contacts));
  row('kinetic energy', text(f.kinetic_energy) + ' J');
  row('elastic energy', text(f.elastic_energy) + ' J');
  row('step time', text(f.step_ms) + ' ms');
  data.bodies.forEach((body, b) => {
    const v = f.volumes[b];
    const fraction = v === null || !(body.rest_volume > 0) ? null : v / body.rest_volume;
    row('volume ' + body.name, fraction === null ? 'open' : text(100 * fraction) + '% of rest',
        fraction !== null && body.keeps_volume && Math.abs(fraction - 1) > data.volume_limit);
  });
  for (const problem of f.problems) row('flagged', problem, true);
}
slider.addEventListener('input', () => show(+slider.value));
document.addEventListener('keydown', (event) => {
  if (event.target === slider) return;
  if (event.key === 'ArrowRight') show(+slider.value + 1);
  if (event.key === 'ArrowLeft') show(+slider.value - 1);
});
for (const link of document.querySelectorAll('[data-index]'))
  link.addEventListener('click', () => show(+link.dataset.index));
let timer = null;
play.addEventListener('click', () => {
  if (timer) {
    clearInterval(timer);
    timer = null;
    play.textContent = 'play';
    return;
  }
  if (+slider.value >= data.frames.length - 1) show(0);
  play.textContent = 'pause';
  timer = setInterval(() => {
    if (+slider.value >= data.frames.length - 1) play.click();
    else show(+slider.value + 1);
  }, 1000 / Math.min(data.fps, 30));
});
show(+slider.value);
document.body.dataset.ready = 'true';
)";

std::string number(double value, int digits = 4) {
  if (!std::isfinite(value)) return "–";
  char text[48];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

std::string signedPercent(double fraction) {
  char text[48];
  std::snprintf(text, sizeof text, "%+.2f%%", 100 * fraction);
  return text;
}

/// A closed body's volume at `record` as a fraction of its rest volume; NaN where it has none.
double volumeFraction(const BakeReport& report, const FrameStats& record, std::size_t body) {
  const BakeReportBody& b = report.bodies[body];
  if (!b.closed || !(b.restVolume > 0) || body >= record.volumes.size() ||
      !std::isfinite(record.volumes[body]))
    return kNaN;
  return record.volumes[body] / b.restVolume;
}

/// What looks wrong in one recorded frame.
struct FrameFlags {
  bool volume = false, energy = false, atCap = false;
  std::vector<std::string> problems;
  bool any() const { return volume || energy || atCap; }
};

std::vector<FrameFlags> flagFrames(const BakeReport& report) {
  std::vector<FrameFlags> flags(report.records.size());
  double peakMotion = 0;  // the largest kinetic plus elastic energy up to the frame
  for (std::size_t i = 0; i < report.records.size(); ++i) {
    const FrameStats& r = report.records[i];
    FrameFlags& f = flags[i];
    std::size_t beyond = 0;
    for (std::size_t b = 0; b < report.bodies.size(); ++b) {
      const double fraction = volumeFraction(report, r, b);
      if (!report.bodies[b].keepsVolume || !(std::abs(fraction - 1) > kReportVolumeLimit)) continue;
      if (++beyond <= 3)
        f.problems.push_back(cat("volume of '", report.bodies[b].name, "' ",
                                 signedPercent(fraction - 1), " from rest"));
    }
    if (beyond > 3)
      f.problems.push_back(
          cat("and ", beyond - 3, " more bodies' volumes beyond ±", 100 * kReportVolumeLimit, "%"));
    f.volume = beyond > 0;
    const double motion = r.kineticEnergy + std::abs(r.elasticEnergy);
    if (std::isfinite(motion)) peakMotion = std::max(peakMotion, motion);
    if (i > 0 && report.records[i - 1].frame == r.frame - 1) {
      const double rise = r.totalEnergy() - report.records[i - 1].totalEnergy();
      if (rise > 0 && rise > kReportEnergyRise * peakMotion) {
        f.energy = true;
        f.problems.push_back(cat("energy rose by ", number(rise, 3), " J, ",
                                 number(100 * rise / peakMotion, 3),
                                 "% of the largest kinetic and elastic energy so far"));
      }
    }
    if (report.substepCap && r.stepped && r.substeps >= *report.substepCap) {
      f.atCap = true;
      f.problems.push_back(cat("substeps at the cap (", *report.substepCap, ")"));
    }
  }
  return flags;
}

/// Bodies in the order the report lists them: closed ones by their largest volume change, the
/// largest first, then the open ones.
struct BodyChange {
  std::size_t body = 0;
  double worst = kNaN;  ///< the largest |V/V_rest − 1|, signed
  int worstFrame = 0;
  double last = kNaN;
};

std::vector<BodyChange> bodyChanges(const BakeReport& report) {
  std::vector<BodyChange> changes(report.bodies.size());
  for (std::size_t b = 0; b < report.bodies.size(); ++b) {
    BodyChange& c = changes[b];
    c.body = b;
    for (const FrameStats& r : report.records) {
      const double change = volumeFraction(report, r, b) - 1;
      if (!std::isfinite(change)) continue;
      if (!std::isfinite(c.worst) || std::abs(change) > std::abs(c.worst)) {
        c.worst = change;
        c.worstFrame = r.frame;
      }
      c.last = change;
    }
  }
  std::stable_sort(changes.begin(), changes.end(), [](const BodyChange& a, const BodyChange& b) {
    const bool aHas = std::isfinite(a.worst), bHas = std::isfinite(b.worst);
    if (aHas != bHas) return aHas;
    return aHas && std::abs(a.worst) > std::abs(b.worst);
  });
  return changes;
}

/// "1–12, 15, 20–24": frame numbers as ranges.
std::string frameRanges(const std::vector<int>& frames) {
  std::string text;
  for (std::size_t i = 0; i < frames.size();) {
    std::size_t j = i;
    while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
    text += cat(text.empty() ? "" : ", ", frames[i]);
    if (j > i) text += cat("–", frames[j]);
    i = j + 1;
  }
  return text;
}

/// The largest of `value(record)` over the records that have one, and its frame.
template <class Value>
std::pair<double, int> peak(const std::vector<FrameStats>& records, Value&& value) {
  double best = kNaN;
  int frame = 0;
  for (const FrameStats& r : records) {
    const double v = value(r);
    if (std::isfinite(v) && (!std::isfinite(best) || v > best)) best = v, frame = r.frame;
  }
  return {best, frame};
}

/// "12 at frame 4": counts in full, measures to 4 digits.
std::string peakText(const std::pair<double, int>& p, const std::string& unit) {
  if (!std::isfinite(p.first)) return "–";
  return cat(number(p.first, unit.empty() ? 15 : 4), unit, " at frame ", p.second);
}

/// `source` in the report's folder as `target`: a hard link where the file system allows (a
/// report of a long shot costs no space), else a copy; through a temporary name either way.
void placeFrame(const fs::path& source, const fs::path& target) {
  std::error_code error;
  if (fs::equivalent(source, target, error)) return;  // already this file: rename would no-op
  const fs::path temporary =
      target.parent_path() / cat(".", target.filename().string(), ".tmp-", ::getpid());
  fs::remove(temporary, error);
  fs::create_hard_link(source, temporary, error);
  if (error) {
    std::ifstream in(source, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (!in.good() && !in.eof())
      throw OutputFailure(cat("cannot read '", source.string(), "' for the report"));
    writeFileAtomically(target, bytes);
    return;
  }
  fs::rename(temporary, target, error);
  if (error) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw OutputFailure(cat("cannot write '", target.string(), "': ", error.message()));
  }
}

/// The report's copies of the PNG frames, by frame number, relative to `folder`; images an
/// earlier report left in `folder`/frames that this one does not show are removed.
std::vector<std::pair<int, std::string>> placeFrames(const fs::path& folder,
                                                     const BakeReport& report) {
  std::vector<std::pair<int, std::string>> placed;
  if (report.pngFrames.empty() && !fs::exists(folder / "frames")) return placed;
  makeDirectories(folder / "frames");
  std::set<std::string> names;
  for (const auto& [frame, source] : report.pngFrames) {
    const std::string name = source.filename().string();
    placeFrame(source, folder / "frames" / name);
    names.insert(name);
    placed.emplace_back(frame, "frames/" + name);
  }
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder / "frames", error))
    if (entry.path().extension() == ".png" && !names.count(entry.path().filename().string()))
      fs::remove(entry.path(), error);
  return placed;
}

/// `json` for a <script> element: no "<" that could end it or open a comment, and a body name
/// that is not UTF-8 (a mesh file's) with U+FFFD where it is not.
std::string scriptData(const Json& json) {
  std::string text;
  for (const char c : json.dump(-1, ' ', false, Json::error_handler_t::replace))
    text += c == '<' ? std::string("\\u003c") : std::string(1, c);
  return text;
}

Json numberOrNull(double value) {
  return std::isfinite(value) ? Json(value) : Json(nullptr);
}

}  // namespace

void writeBakeReport(const fs::path& folder, const BakeReport& report) {
  makeDirectories(folder);
  const std::vector<FrameStats>& records = report.records;
  const std::vector<FrameFlags> flags = flagFrames(report);
  const std::vector<BodyChange> changes = bodyChanges(report);
  const std::vector<std::pair<int, std::string>> images = placeFrames(folder, report);

  // Which bodies the charts and the flipbook show: the ones whose volume changed most.
  std::vector<std::size_t> plotted;
  for (const BodyChange& c : changes)
    if (std::isfinite(c.worst) && plotted.size() < kPlottedBodies) plotted.push_back(c.body);
  std::sort(plotted.begin(), plotted.end());
  const std::size_t closedBodies =
      std::size_t(std::count_if(report.bodies.begin(), report.bodies.end(),
                                [](const BakeReportBody& b) { return b.closed; }));

  std::vector<int> flaggedFrames, volumeFrames, energyFrames, capFrames;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (flags[i].any()) flaggedFrames.push_back(records[i].frame);
    if (flags[i].volume) volumeFrames.push_back(records[i].frame);
    if (flags[i].energy) energyFrames.push_back(records[i].frame);
    if (flags[i].atCap) capFrames.push_back(records[i].frame);
  }
  const auto withFailure = [&](std::vector<int> frames) {
    if (report.failedFrame > 0) frames.push_back(report.failedFrame);
    return frames;
  };

  // The headline: a failure first, then flagged frames.
  std::string headline, verdict;
  if (report.failedFrame > 0) {
    headline = cat("blew up at frame ", report.failedFrame);
    verdict = "fail";
  } else if (!report.failure.empty()) {
    headline = cat("failed: ", report.failure);
    verdict = "fail";
  } else if (!flaggedFrames.empty()) {
    headline = cat(flaggedFrames.size(), " of ", records.size(), " frames flagged");
    verdict = "warn";
  } else {
    headline = cat("no frame flagged in ", records.size(), " frames");
    verdict = "pass";
  }
  if (report.status == "interrupted") headline += ", interrupted";
  if (report.failedFrame > 0 && !flaggedFrames.empty())
    headline += cat("; ", flaggedFrames.size(), " frames flagged before it");

  std::string html =
      cat(reportPageStart(cat("softbake run: ", report.scene, ": ", headline), kStyle),
          "<h1>softbake bake report: ", escapeMarkup(report.scene), "</h1>\n<p class=\"headline ",
          verdict, "\" id=\"headline\">", escapeMarkup(headline),
          "</p>\n<p id=\"broken\" hidden></p>\n<table class=\"summary\" id=\"summary\">\n");
  html += summaryRow("scene", report.input.empty() ? cat(report.scene, " (built-in)")
                                                   : cat(report.scene, " (", report.input, ")"));
  html += summaryRow("output", report.out.string());
  html += summaryRow(
      "status", report.failure.empty() ? report.status : cat(report.status, ": ", report.failure));
  std::vector<int> recordedFrames, unrecorded;
  for (const FrameStats& r : records) recordedFrames.push_back(r.frame);
  const int lastRecorded = records.empty() ? 0 : records.back().frame;
  for (int frame = 1, i = 0; frame <= lastRecorded; ++frame) {
    if (std::size_t(i) < records.size() && records[std::size_t(i)].frame == frame)
      ++i;
    else
      unrecorded.push_back(frame);
  }
  html += summaryRow("frames", cat(records.size(), " recorded (", frameRanges(recordedFrames),
                                   ") of ", report.frames, " at ", report.fps, " fps"));
  if (!unrecorded.empty())
    html += summaryRow("not recorded",
                       cat("frames ", frameRanges(unrecorded),
                           ": simulated by an earlier invocation of the run without --report"));
  html += summaryRow("bodies", cat(report.bodies.size(), " (", closedBodies, " closed)"));
  html += summaryRow(
      "integrator",
      cat(report.integrator, ", substeps ", report.substeps,
          report.substepCap ? cat(" (at most ", *report.substepCap, " a frame)") : std::string()));
  double stepMs = 0;
  std::uint64_t substeps = 0;
  for (const FrameStats& r : records)
    if (r.stepped) stepMs += r.stepMs, substeps += std::uint64_t(r.substeps);
  html +=
      summaryRow("wall time", cat(number(report.wallSeconds, 3), " s for this invocation; ",
                                  number(stepMs / 1e3, 3), " s in the recorded frames' substeps"));
  html += summaryRow(
      "substeps",
      cat(substeps, " in all; peak ",
          peakText(peak(records,
                        [](const FrameStats& r) { return r.stepped ? double(r.substeps) : kNaN; }),
                   "")));
  html += summaryRow(
      "peak contacts",
      cat(peakText(peak(records,
                        [](const FrameStats& r) { return r.stepped ? double(r.contacts) : kNaN; }),
                   ""),
          "; plane contacts ",
          peakText(
              peak(records,
                   [](const FrameStats& r) { return r.stepped ? double(r.planeContacts) : kNaN; }),
              ""),
          " (summed over a frame's substeps)"));
  html += summaryRow(
      "peak kinetic energy",
      peakText(peak(records, [](const FrameStats& r) { return r.kineticEnergy; }), " J"));
  html += summaryRow(
      "slowest frame",
      peakText(peak(records, [](const FrameStats& r) { return r.stepped ? r.stepMs : kNaN; }),
               " ms"));
  if (!changes.empty() && std::isfinite(changes.front().worst)) {
    const BodyChange& worst = changes.front();
    html += summaryRow("worst volume change",
                       cat("'", report.bodies[worst.body].name, "' ", signedPercent(worst.worst),
                           " at frame ", worst.worstFrame, " (every closed body below)"));
  }
  html += summaryRow("flagged frames", flaggedFrames.empty()
                                           ? std::string("none")
                                           : cat(flaggedFrames.size(), ": ",
                                                 frameRanges(flaggedFrames), " (listed below)"));
  html += summaryRow(
      "flagged when",
      cat("the volume of a closed body with a bulk modulus is more than ", 100 * kReportVolumeLimit,
          "% from its rest volume (under the gas law alone, bulk_modulus 0, volume follows the "
          "load by design: plotted, not flagged); the total energy (kinetic, elastic, gravity's), "
          "which nothing "
          "in a scene adds, rises in a frame by more than ",
          100 * kReportEnergyRise, "% of the largest kinetic and elastic energy up to it; ",
          report.substepCap ? cat("\"auto\" substeps reach their cap of ", *report.substepCap)
                            : std::string("substeps at a cap (none in this run)")));
  for (const std::string& note : report.notes) html += summaryRow("note", note);
  html += "</table>\n";

  // Where it went wrong, frame by frame.
  if (report.failedFrame > 0 || !flaggedFrames.empty()) {
    html += "<h2>Flagged frames</h2>\n<table class=\"list\" id=\"flagged\">\n";
    // Consecutive frames flagged for the same things are one row, the first of them shown: a
    // body that stays squashed for 90 frames is one finding, not 90.
    const auto alike = [&](std::size_t a, std::size_t b) {
      static const std::regex numbers("[-+]?[0-9][0-9.e+-]*");
      if (records[b].frame != records[a].frame + 1) return false;
      if (flags[a].problems.size() != flags[b].problems.size()) return false;
      for (std::size_t k = 0; k < flags[a].problems.size(); ++k)
        if (std::regex_replace(flags[a].problems[k], numbers, "#") !=
            std::regex_replace(flags[b].problems[k], numbers, "#"))
          return false;
      return true;
    };
    std::size_t listed = 0, rows = 0;
    for (std::size_t i = 0; i < records.size() && rows < kListedFrames; ++i) {
      if (!flags[i].any()) continue;
      std::size_t last = i;
      while (last + 1 < records.size() && flags[last + 1].any() && alike(last, last + 1)) ++last;
      ++rows;
      listed += last - i + 1;
      std::string problems;
      for (const std::string& p : flags[i].problems)
        problems += cat(problems.empty() ? "" : "; ", p);
      if (last > i)
        problems +=
            cat(" (at frame ", records[i].frame, "; frames to ", records[last].frame, " alike)");
      const std::string frames = last > i
                                     ? cat("frames ", records[i].frame, "–", records[last].frame)
                                     : cat("frame ", records[i].frame);
      html += cat("<tr class=\"flagged\" data-frame=\"", records[i].frame,
                  "\"><td><a href=\"#flipbook\" data-index=\"", i, "\">", frames,
                  "</a></td><td class=\"bad\">", escapeMarkup(problems), "</td></tr>\n");
      i = last;
    }
    if (flaggedFrames.size() > listed)
      html +=
          cat("<tr><td></td><td>and ", flaggedFrames.size() - listed, " more frames</td></tr>\n");
    if (report.failedFrame > 0)
      html += cat("<tr class=\"failed\" data-frame=\"", report.failedFrame, "\"><td>frame ",
                  report.failedFrame, "</td><td class=\"bad\">", escapeMarkup(report.failure),
                  "</td></tr>\n");
    html += "</table>\n";
  }

  // Plots: a value per recorded frame, the frames flagged for it marked.
  std::vector<int> frames = recordedFrames;
  const auto series = [&](auto&& value) {
    std::vector<double> values;
    for (const FrameStats& r : records) values.push_back(value(r));
    return values;
  };
  std::vector<Plot> plots;
  plots.push_back({"substeps",
                   "per frame",
                   frames,
                   {"substeps"},
                   {series([](const FrameStats& r) { return r.stepped ? r.substeps : kNaN; })},
                   withFailure(capFrames),
                   {}});
  if (report.substepCap) plots.back().guides.push_back(*report.substepCap);
  plots.push_back(
      {"contacts",
       "summed over the frame's substeps",
       frames,
       {"soft", "plane"},
       {series([](const FrameStats& r) { return r.stepped ? double(r.contacts) : kNaN; }),
        series([](const FrameStats& r) { return r.stepped ? double(r.planeContacts) : kNaN; })},
       withFailure({}),
       {}});
  plots.push_back({"energy",
                   "J",
                   frames,
                   {"kinetic", "elastic"},
                   {series([](const FrameStats& r) { return r.kineticEnergy; }),
                    series([](const FrameStats& r) { return r.elasticEnergy; })},
                   withFailure(energyFrames),
                   {}});
  Plot volume{"volume change",
              "% of rest",
              frames,
              {},
              {},
              withFailure(volumeFrames),
              {-100 * kReportVolumeLimit, 100 * kReportVolumeLimit}};
  for (const std::size_t b : plotted) {
    volume.names.push_back(report.bodies[b].name);
    volume.series.push_back(
        series([&](const FrameStats& r) { return 100 * (volumeFraction(report, r, b) - 1); }));
  }
  plots.push_back(std::move(volume));
  plots.push_back({"step time",
                   "ms of wall time",
                   frames,
                   {"wall time"},
                   {series([](const FrameStats& r) { return r.stepped ? r.stepMs : kNaN; })},
                   withFailure({}),
                   {}});
  html += "<h2>Per frame</h2>\n<section id=\"plots\">\n";
  const char* ids[] = {"substeps", "contacts", "energy", "volume", "step-time"};
  for (std::size_t p = 0; p < plots.size(); ++p)
    html += cat("<figure class=\"plot\" id=\"plot-", ids[p], "\">\n", svgLineChart(plots[p]),
                "</figure>\n");
  if (closedBodies > plotted.size())
    html += cat("<p>The ", plotted.size(), " of ", closedBodies,
                " closed bodies whose volume changed most are drawn; every body's volume per "
                "frame is in ",
                escapeMarkup((report.out / "frame_stats.jsonl").string()), ".</p>\n");
  if (closedBodies == 0) html += "<p>No body is closed: none has a volume.</p>\n";
  html += "</section>\n";

  // The flipbook, on the first frame flagged (or the last one before a failure).
  std::size_t first = 0;
  const auto firstFlagged =
      std::find_if(flags.begin(), flags.end(), [](const FrameFlags& f) { return f.any(); });
  if (firstFlagged != flags.end())
    first = std::size_t(firstFlagged - flags.begin());
  else if (report.failedFrame > 0 && !records.empty())
    first = records.size() - 1;
  std::map<int, std::string> imageOf(images.begin(), images.end());
  html += "<h2>Flipbook</h2>\n";
  if (images.empty())
    html += cat("<p id=\"no-frames\">No PNG frames: ",
                report.status == "complete"
                    ? "this run wrote none (--render renders them; softbake export --png "
                      "writes them from the cache)."
                    : "PNG frames are rendered once the whole shot is simulated, and this run "
                      "stopped before (--render-while-simulating renders each frame as it is "
                      "simulated). The numbers of each frame are below.",
                "</p>\n");
  html += "<div id=\"flipbook\">\n<div id=\"flip-view\">\n";
  if (!images.empty()) {
    const auto shown = imageOf.find(records.empty() ? 0 : records[first].frame);
    html += cat("<img id=\"flip-image\" src=\"",
                escapeMarkup(shown != imageOf.end() ? shown->second : images.front().second),
                "\" alt=\"the frame\">\n<div id=\"flip-missing\" hidden>no PNG of this "
                "frame</div>\n");
  }
  html += "<div id=\"flip-track\">";
  const double span = double(std::max<std::size_t>(records.size(), 2) - 1);
  for (std::size_t i = 0; i < records.size(); ++i)
    if (flags[i].any())
      html += cat("<span data-index=\"", i, "\" style=\"left:", number(100 * double(i) / span),
                  "%\" title=\"frame ", records[i].frame, "\"></span>");
  html += cat("</div>\n<input id=\"flip-slider\" type=\"range\" min=\"0\" max=\"",
              records.empty() ? 0 : records.size() - 1, "\" value=\"", first,
              "\" aria-label=\"frame\">\n<div><button id=\"flip-play\" type=\"button\">play"
              "</button> <span id=\"flip-frame\"></span> (arrow keys step a frame)</div>\n"
              "</div>\n<table id=\"flip-numbers\"></table>\n</div>\n");

  // Every closed body's volume, the worst first.
  html +=
      "<h2>Bodies</h2>\n<table class=\"list\" id=\"bodies\">\n<tr><th>body</th><th>rest "
      "volume</th><th>largest change</th><th>at frame</th><th>last recorded</th></tr>\n";
  std::size_t listedBodies = 0;
  for (const BodyChange& c : changes) {
    if (listedBodies++ == kListedBodies) break;
    const BakeReportBody& body = report.bodies[c.body];
    const bool bad = body.keepsVolume && std::abs(c.worst) > kReportVolumeLimit;
    html += cat("<tr class=\"body\" data-body=\"", escapeMarkup(body.name), "\"><td>",
                escapeMarkup(body.name), "</td>");
    if (!std::isfinite(c.worst))
      html +=
          cat("<td colspan=\"4\">", body.closed ? "no record" : "open: no volume", "</td></tr>\n");
    else
      html += cat("<td>", number(body.restVolume), "</td><td", bad ? " class=\"bad\"" : "", ">",
                  signedPercent(c.worst), "</td><td>", c.worstFrame, "</td><td>",
                  signedPercent(c.last), "</td></tr>\n");
  }
  html += "</table>\n";
  if (report.bodies.size() > kListedBodies)
    html += cat("<p>The ", kListedBodies, " bodies whose volume changed most, of ",
                report.bodies.size(), ".</p>\n");

  // The numbers the flipbook shows, and a script or a person can read.
  Json data;
  data["scene"] = report.scene;
  data["fps"] = report.fps;
  data["volume_limit"] = kReportVolumeLimit;
  data["failed_frame"] = report.failedFrame > 0 ? Json(report.failedFrame) : Json(nullptr);
  Json bodies = Json::array();
  for (const std::size_t b : plotted)
    bodies.push_back({{"name", report.bodies[b].name},
                      {"index", b},
                      {"rest_volume", report.bodies[b].restVolume},
                      {"keeps_volume", report.bodies[b].keepsVolume}});
  data["bodies"] = std::move(bodies);
  Json frameData = Json::array();
  for (std::size_t i = 0; i < records.size(); ++i) {
    const FrameStats& r = records[i];
    Json f;
    f["frame"] = r.frame;
    f["substeps"] = r.stepped ? Json(r.substeps) : Json(nullptr);
    f["at_cap"] = flags[i].atCap;
    f["contacts"] = r.stepped ? Json(r.contacts) : Json(nullptr);
    f["plane_contacts"] = r.stepped ? Json(r.planeContacts) : Json(nullptr);
    f["step_ms"] = r.stepped ? numberOrNull(r.stepMs) : Json(nullptr);
    f["kinetic_energy"] = numberOrNull(r.kineticEnergy);
    f["elastic_energy"] = numberOrNull(r.elasticEnergy);
    Json volumes = Json::array();
    for (const std::size_t b : plotted)
      volumes.push_back(numberOrNull(b < r.volumes.size() ? r.volumes[b] : kNaN));
    f["volumes"] = std::move(volumes);
    const auto image = imageOf.find(r.frame);
    f["image"] = image != imageOf.end() ? Json(image->second) : Json(nullptr);
    f["problems"] = flags[i].problems;
    frameData.push_back(std::move(f));
  }
  data["frames"] = std::move(frameData);
  html +=
      cat("<script type=\"application/json\" id=\"frame-data\">", scriptData(data), "</script>\n");
  html += reportPageEnd(records.empty() ? "" : kScript);
  writeFileAtomically(folder / "index.html", html);
}

}  // namespace softbake
