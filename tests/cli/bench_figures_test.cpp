// `softbake bench`'s figures checked against each other and against what was asked for: the
// machine-readable line, the per-step CSV and --warmup. No figure is compared with a time this
// machine should reach; only their consistency is.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "softbake_process.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using test::CliTest;
using test::quoted;
using test::readFile;
using test::Result;
using test::runSoftbake;

/// The machine-readable lines, `key=value` words, one map per broad phase.
std::vector<std::map<std::string, std::string>> summaryLines(const std::string& output) {
  std::vector<std::map<std::string, std::string>> lines;
  std::istringstream text(output);
  for (std::string line; std::getline(text, line);) {
    if (line.rfind("scene=", 0) != 0) continue;
    std::map<std::string, std::string> fields;
    std::istringstream words(line);
    for (std::string word; words >> word;) {
      const std::size_t equals = word.find('=');
      if (equals != std::string::npos) fields[word.substr(0, equals)] = word.substr(equals + 1);
    }
    lines.push_back(fields);
  }
  return lines;
}

double number(const std::map<std::string, std::string>& fields, const std::string& key) {
  const auto found = fields.find(key);
  if (found == fields.end()) {
    ADD_FAILURE() << "no " << key;
    return NAN;
  }
  return std::stod(found->second);
}

struct CsvRow {
  std::string broadPhase;
  long step = 0, frame = 0;
  std::vector<double> stagesMs;  ///< forces … contacts
  double stepMs = 0;
  long pairs = 0, contacts = 0;
};

/// The stages the header names, forces to contacts.
constexpr int kStages = 9;
constexpr const char* kCsvHeader =
    "broadphase,step,frame,forces_ms,integration_ms,boxes_ms,broad_phase_ms,narrow_phase_ms,"
    "response_ms,planes_ms,failsafe_ms,contacts_ms,step_ms,pairs,contacts";

std::vector<CsvRow> readCsv(const fs::path& path) {
  std::istringstream text(readFile(path));
  std::string line;
  std::getline(text, line);
  EXPECT_EQ(line, kCsvHeader);
  std::vector<CsvRow> rows;
  while (std::getline(text, line)) {
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    EXPECT_EQ(cells.size(), std::size_t(6 + kStages)) << line;
    if (cells.size() != 6 + kStages) continue;
    CsvRow parsed;
    parsed.broadPhase = cells[0];
    parsed.step = std::stol(cells[1]);
    parsed.frame = std::stol(cells[2]);
    for (int stage = 0; stage < kStages; ++stage)
      parsed.stagesMs.push_back(std::stod(cells[3 + stage]));
    parsed.stepMs = std::stod(cells[3 + kStages]);
    parsed.pairs = std::stol(cells[4 + kStages]);
    parsed.contacts = std::stol(cells[5 + kStages]);
    rows.push_back(parsed);
  }
  return rows;
}

/// The value at nearest rank floor(fraction · n), as bench computes its median and p95.
double rank(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, std::size_t(fraction * double(values.size())))];
}

class BenchFigures : public CliTest {};

TEST_F(BenchFigures, TheSummaryLineAndTheCsvAgree) {
  // 4 frames after the first, 4 substeps each: 16 steps per broad phase.
  constexpr int kFrames = 5, kSubsteps = 4, kSteps = (kFrames - 1) * kSubsteps;
  const fs::path csv = folder_ / "steps.csv";
  const Result run =
      runSoftbake("bench default --frames " + std::to_string(kFrames) + " --substeps " +
                  std::to_string(kSubsteps) + " --broadphase sbhash,bvh -j 1 --csv " + quoted(csv));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const auto lines = summaryLines(run.output);
  ASSERT_EQ(lines.size(), 2u) << run.output;
  const std::vector<CsvRow> rows = readCsv(csv);
  ASSERT_EQ(rows.size(), std::size_t(2 * kSteps));

  const char* broadPhases[] = {"sbhash", "bvh"};
  for (int b = 0; b < 2; ++b) {
    const auto& line = lines[std::size_t(b)];
    SCOPED_TRACE(broadPhases[b]);
    EXPECT_EQ(line.at("scene"), "default");
    EXPECT_EQ(line.at("broadphase"), broadPhases[b]);
    EXPECT_EQ(number(line, "faces"), 2 * 1280);  // two level-3 icospheres
    EXPECT_EQ(number(line, "threads"), 1);
    EXPECT_EQ(number(line, "warmup"), 0);
    EXPECT_EQ(number(line, "steps"), kSteps);
    // Both rates come from the same simulated seconds: frames/s is steps/s over the substeps per
    // frame, up to the rounding of the printed figures (0.05 and 0.005).
    const double stepsPerSecond = number(line, "steps_per_s");
    const double framesPerSecond = number(line, "frames_per_s");
    EXPECT_GT(stepsPerSecond, 0);
    EXPECT_GT(framesPerSecond, 0);
    EXPECT_NEAR(framesPerSecond * kSubsteps, stepsPerSecond, 0.05 + kSubsteps * 0.005);

    std::vector<double> stepMs;
    double contacts = 0;
    for (int s = 0; s < kSteps; ++s) {
      const CsvRow& row = rows[std::size_t(b * kSteps + s)];
      EXPECT_EQ(row.broadPhase, broadPhases[b]);
      EXPECT_EQ(row.step, s + 1);
      EXPECT_EQ(row.frame, 2 + s / kSubsteps);
      // The step is its stages, each printed to 6 significant digits.
      double stages = 0;
      for (double ms : row.stagesMs) {
        EXPECT_GE(ms, 0);
        stages += ms;
      }
      EXPECT_GT(row.stepMs, 0);
      EXPECT_NEAR(stages, row.stepMs, 1e-5 * row.stepMs + 1e-9) << "step " << s + 1;
      // Every broad phase finds the same pairs, so the simulations and their counts agree.
      const CsvRow& sbhash = rows[std::size_t(s)];
      EXPECT_EQ(row.pairs, sbhash.pairs);
      EXPECT_EQ(row.contacts, sbhash.contacts);
      stepMs.push_back(row.stepMs);
      contacts += double(row.contacts);
    }
    // The line's spread is the CSV's, printed to 4 decimals.
    EXPECT_NEAR(number(line, "median_step_ms"), rank(stepMs, 0.5), 6e-5 + 1e-5 * rank(stepMs, 0.5));
    EXPECT_NEAR(number(line, "p95_step_ms"), rank(stepMs, 0.95), 6e-5 + 1e-5 * rank(stepMs, 0.95));
    EXPECT_NEAR(number(line, "contacts_per_step"), contacts / kSteps, 0.05);
    EXPECT_GT(number(line, "peak_rss_mb"), 0);
  }
}

TEST_F(BenchFigures, WarmupStepsRunFirstAndAreNotMeasured) {
  // The built-in scene's balls are apart for their first quarter second and in contact from about
  // 0.2 s to 0.45 s: the 8 measured steps (1/12 s) see contacts only after a warm-up has brought
  // the balls together.
  const auto contactsAfter = [&](int warmup) -> double {
    const Result run =
        runSoftbake("bench default --frames 3 --substeps 4 --warmup " + std::to_string(warmup));
    EXPECT_EQ(run.exitCode, 0) << run.output;
    const auto lines = summaryLines(run.output);
    EXPECT_EQ(lines.size(), 1u) << run.output;
    if (lines.size() != 1) return NAN;
    EXPECT_EQ(number(lines[0], "warmup"), warmup);
    EXPECT_EQ(number(lines[0], "steps"), 8) << "warm-up steps are not counted";
    if (warmup > 0) {
      EXPECT_NE(run.output.find("after " + std::to_string(warmup) + " warm-up steps"),
                std::string::npos)
          << run.output;
    }
    return number(lines[0], "contacts_per_step");
  };
  EXPECT_EQ(contactsAfter(0), 0);
  EXPECT_GT(contactsAfter(32), 0);  // 1/3 s: the balls press into each other
}

/// The volume enclosed by each object ("o" line) of an OBJ file, by the divergence theorem, in
/// double: an independent reading of what the simulation wrote.
std::vector<double> objectVolumes(const fs::path& path) {
  std::istringstream text(readFile(path));
  std::vector<std::array<double, 3>> vertices;
  std::vector<double> volumes;
  for (std::string line; std::getline(text, line);) {
    std::istringstream words(line);
    std::string tag;
    words >> tag;
    if (tag == "o") volumes.push_back(0);
    if (tag == "v") {
      std::array<double, 3>& v = vertices.emplace_back();
      words >> v[0] >> v[1] >> v[2];
    }
    if (tag == "f" && !volumes.empty()) {
      std::array<std::array<double, 3>, 3> corner;
      for (auto& c : corner) {
        std::string reference;
        words >> reference;  // v/vt/vn: the position index comes first
        c = vertices.at(std::stoul(reference) - 1);
      }
      const auto& [a, b, c] = corner;
      volumes.back() += (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                         a[2] * (b[0] * c[1] - b[1] * c[0])) /
                        6;
    }
  }
  return volumes;
}

TEST_F(BenchFigures, MaxVolumeErrorIsTheWorstFrameOfTheWrittenBodies) {
  // The built-in balls squash each other from about frame 6: the figure is the largest
  // |V/V_rest − 1| over every body and frame, as the OBJ frames of the same run show it (their
  // first frame is the rest shape; 6 significant digits per coordinate).
  constexpr int kFrames = 16;
  const Result bench = runSoftbake("bench default --frames " + std::to_string(kFrames));
  ASSERT_EQ(bench.exitCode, 0) << bench.output;
  const auto lines = summaryLines(bench.output);
  ASSERT_EQ(lines.size(), 1u) << bench.output;
  const double reported = number(lines[0], "max_volume_error");
  const Result run = runSoftbake("run --frames " + std::to_string(kFrames) + " --no-render -q -o " +
                                 quoted((folder_ / "out").string()));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const std::vector<double> rest = objectVolumes(folder_ / "out/obj/default_0001.obj");
  ASSERT_EQ(rest.size(), 2u);
  double worst = 0;
  for (int frame = 2; frame <= kFrames; ++frame) {
    char name[32];
    std::snprintf(name, sizeof name, "out/obj/default_%04d.obj", frame);
    const std::vector<double> volumes = objectVolumes(folder_ / name);
    ASSERT_EQ(volumes.size(), rest.size());
    for (std::size_t b = 0; b < rest.size(); ++b)
      worst = std::max(worst, std::abs(volumes[b] / rest[b] - 1));
  }
  EXPECT_GT(worst, 0.001) << "the balls should squash each other in these frames";
  EXPECT_NEAR(reported, worst, 2e-4);
}

TEST_F(BenchFigures, FramesAndBroadPhasesAreTheTablesRowsAsRunTakesThem) {
  // bench takes --frames and --broadphase from the option table, as run does: the same words
  // refuse the same value, and a value lands as the scene key does (frames 3: 2 measured frames).
  const std::string refusal =
      "--broadphase: expected 'sbhash', 'spatialhash', 'bvh' or 'brute', "
      "got 'octree'";
  for (const char* command : {"run --no-render -q -o ", "bench default --csv "}) {
    const Result bad = runSoftbake(std::string(command) + quoted((folder_ / "x").string()) +
                                   " --broadphase octree");
    EXPECT_EQ(bad.exitCode, 1) << bad.output;
    EXPECT_NE(bad.output.find(refusal), std::string::npos) << command << bad.output;
  }
  // One element of a list is checked as one value is.
  const Result badInList = runSoftbake("bench default --broadphase bvh,octree");
  EXPECT_EQ(badInList.exitCode, 1) << badInList.output;
  EXPECT_NE(badInList.output.find(refusal), std::string::npos) << badInList.output;
  const Result tooMany = runSoftbake("bench default --frames 0");
  EXPECT_EQ(tooMany.exitCode, 1) << tooMany.output;
  EXPECT_NE(tooMany.output.find("--frames: expected a whole number from 1 to 10000000, got '0'"),
            std::string::npos)
      << tooMany.output;
  const Result one = runSoftbake("bench default --frames 1");
  EXPECT_EQ(one.exitCode, 1) << one.output;
  EXPECT_NE(one.output.find("at least 2 --frames"), std::string::npos) << one.output;

  const Result run = runSoftbake("bench default --frames 3 --substeps 2 --broadphase brute,bvh");
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const auto lines = summaryLines(run.output);
  ASSERT_EQ(lines.size(), 2u) << run.output;
  EXPECT_EQ(lines[0].at("broadphase"), "brute");
  EXPECT_EQ(lines[1].at("broadphase"), "bvh");
  for (const auto& line : lines) EXPECT_EQ(number(line, "steps"), 2 * 2);
}

}  // namespace
}  // namespace softbake
