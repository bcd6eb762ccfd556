// `softbake run --report DIR`: the bake report, through the real binary. Its numbers are checked
// against what the run's own files give, recomputed here without softbake's code (volumes from
// the OBJ frames, kinetic energy from the cache's velocities and masses from the first frame's
// areas); a run that blows up still reports, naming the frame; a resumed run reports every frame;
// and Debian's chromium opens the report from disk, offline (check_report.py). The screenshot
// stays in SOFTBAKE_TEST_ARTIFACTS_DIR/bake_report.png for a person to look at.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/compare/check_report.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using test::checkReport;
using test::quoted;
using test::readFile;
using test::runSoftbake;

/// The data the report's page holds: what its flipbook shows and its plots are drawn from.
Json reportData(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"frame-data\">";
  const std::size_t start = html.find(open);
  if (start == std::string::npos) return Json();
  const std::size_t end = html.find("</script>", start);
  return Json::parse(html.substr(start + open.size(), end - start - open.size()));
}

/// The text of the element with `id` (an SVG plot's <figure>, the flagged frames' table).
std::string element(const std::string& html, const std::string& id, const std::string& tag) {
  const std::size_t start = html.find("id=\"" + id + "\"");
  if (start == std::string::npos) return {};
  return html.substr(start, html.find("</" + tag + ">", start) - start);
}

/// The number of points of each line of a plot.
std::vector<std::size_t> linePoints(const std::string& figure) {
  std::vector<std::size_t> counts;
  static const std::regex line("<polyline[^>]* points=\"([^\"]*)\"");
  for (std::sregex_iterator it(figure.begin(), figure.end(), line), last; it != last; ++it) {
    std::istringstream points((*it)[1].str());
    std::string point;
    std::size_t count = 0;
    while (points >> point) ++count;
    counts.push_back(count);
  }
  return counts;
}

struct ObjBody {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::size_t, 3>> triangles;  ///< into `vertices`
};

/// The bodies of an OBJ frame, one per `o` block, their faces' `v` indices made local.
std::vector<ObjBody> readObj(const fs::path& path) {
  std::vector<ObjBody> bodies;
  std::istringstream lines(readFile(path));
  std::string line;
  std::size_t before = 0;  // vertices of the earlier blocks
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string kind;
    words >> kind;
    if (kind == "o") {
      if (!bodies.empty()) before += bodies.back().vertices.size();
      bodies.emplace_back();
    } else if (kind == "v") {
      std::array<double, 3> v{};
      words >> v[0] >> v[1] >> v[2];
      bodies.back().vertices.push_back(v);
    } else if (kind == "f") {
      std::array<std::size_t, 3> t{};
      for (std::size_t& corner : t) {
        std::string word;
        words >> word;
        corner = std::stoul(word.substr(0, word.find('/'))) - 1 - before;
      }
      bodies.back().triangles.push_back(t);
    }
  }
  return bodies;
}

using Vec = std::array<double, 3>;
Vec minus(const Vec& a, const Vec& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// The enclosed volume, by the divergence theorem.
double volume(const ObjBody& body) {
  double sum = 0;
  for (const auto& t : body.triangles)
    sum += dot(body.vertices[t[0]], cross(body.vertices[t[1]], body.vertices[t[2]])) / 6;
  return sum;
}

/// Each particle's share of `mass`: a third of the area of each triangle it is a corner of.
std::vector<double> particleMasses(const ObjBody& body, double mass) {
  std::vector<double> area(body.vertices.size(), 0);
  double total = 0;
  for (const auto& t : body.triangles) {
    const Vec n = cross(minus(body.vertices[t[1]], body.vertices[t[0]]),
                        minus(body.vertices[t[2]], body.vertices[t[0]]));
    const double a = 0.5 * std::sqrt(dot(n, n));
    for (const std::size_t v : t) area[v] += a / 3;
    total += a;
  }
  for (double& a : area) a = mass * a / total;
  return area;
}

/// A cache frame's velocities (docs/outputs.md: 64-byte header, positions, then velocities as
/// float32 triples).
std::vector<Vec> cacheVelocities(const fs::path& path) {
  const std::string bytes = readFile(path);
  std::uint32_t particles = 0;
  std::memcpy(&particles, bytes.data() + 20, 4);
  std::vector<Vec> velocities(particles);
  for (std::size_t i = 0; i < particles; ++i)
    for (std::size_t c = 0; c < 3; ++c) {
      float v = 0;
      std::memcpy(&v, bytes.data() + 64 + 12 * std::size_t(particles) + 12 * i + 4 * c, 4);
      velocities[i][c] = v;
    }
  return velocities;
}

std::string frameName(const char* format, int frame) {
  char name[64];
  std::snprintf(name, sizeof name, format, frame);
  return name;
}

std::set<std::string> filesIn(const fs::path& folder) {
  std::set<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder))
    names.insert(entry.path().filename().string());
  return names;
}

std::size_t lineCount(const fs::path& path) {
  const std::string text = readFile(path);
  return std::size_t(std::count(text.begin(), text.end(), '\n'));
}

using BakeReport = test::CliTest;

TEST_F(BakeReport, ARunRecordsEveryFrameWithTheVolumesAndEnergyItsObjAndCacheFramesGive) {
  const fs::path out = folder_ / "out", report = folder_ / "report";
  const test::Result run = runSoftbake("run --frames 12 --size 96x54 -q --out " + quoted(out) +
                                       " --report " + quoted(report));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("report: " + (report / "index.html").string()), std::string::npos)
      << run.output;
  const std::string html = readFile(report / "index.html");
  const Json data = reportData(html);
  ASSERT_TRUE(data.is_object()) << html.substr(0, 2000);

  // One record per frame, in the page and in OUT, frame 1 (the initial state) included.
  ASSERT_EQ(data["frames"].size(), 12u);
  EXPECT_EQ(lineCount(out / "frame_stats.jsonl"), 12u);
  for (int f = 1; f <= 12; ++f) EXPECT_EQ(data["frames"][f - 1]["frame"], f);
  EXPECT_TRUE(data["frames"][0]["substeps"].is_null());
  EXPECT_GE(data["frames"][1]["substeps"].get<int>(), 1);

  // Volumes as the OBJ frames give them; kinetic energy as the cache's velocities do, with the
  // masses the scene gives each body spread over its particles by area. Within a part in a
  // million: softbake sums float products, this test double ones.
  const Json scene = Json::parse(runSoftbake("scene default", false).output);
  const std::vector<ObjBody> rest = readObj(out / "obj/default_0001.obj");
  ASSERT_EQ(rest.size(), 2u);
  ASSERT_EQ(data["bodies"].size(), 2u);
  std::vector<double> masses;
  for (std::size_t b = 0; b < rest.size(); ++b) {
    const std::vector<double> share =
        particleMasses(rest[b], scene["bodies"][b]["mass"].get<double>());
    masses.insert(masses.end(), share.begin(), share.end());
    EXPECT_EQ(data["bodies"][b]["index"], b);
    EXPECT_NEAR(data["bodies"][b]["rest_volume"].get<double>(), volume(rest[b]),
                1e-6 * volume(rest[b]));
  }
  for (int f = 1; f <= 12; ++f) {
    const Json& record = data["frames"][f - 1];
    const std::vector<ObjBody> bodies = readObj(out / ("obj/" + frameName("default_%04d.obj", f)));
    for (std::size_t b = 0; b < bodies.size(); ++b)
      EXPECT_NEAR(record["volumes"][b].get<double>(), volume(bodies[b]), 1e-6 * volume(bodies[b]))
          << "frame " << f << " body " << b;
    const std::vector<Vec> velocities =
        cacheVelocities(out / ("cache/" + frameName("default_%04d.sbframe", f)));
    ASSERT_EQ(velocities.size(), masses.size());
    double kinetic = 0;
    for (std::size_t i = 0; i < masses.size(); ++i)
      kinetic += 0.5 * masses[i] * dot(velocities[i], velocities[i]);
    EXPECT_NEAR(record["kinetic_energy"].get<double>(), kinetic, 1e-6 * kinetic) << "frame " << f;
  }
  // The balls are thrown, so frame 1 already moves: the check above is not of zeros.
  EXPECT_GT(data["frames"][0]["kinetic_energy"].get<double>(), 1.0);

  // The plots draw every record: a line per body over the 12 frames, substeps from frame 2.
  EXPECT_EQ(linePoints(element(html, "plot-volume", "figure")), (std::vector<std::size_t>{12, 12}));
  EXPECT_EQ(linePoints(element(html, "plot-substeps", "figure")), std::vector<std::size_t>{11});
  EXPECT_EQ(linePoints(element(html, "plot-energy", "figure")), (std::vector<std::size_t>{12, 12}));

  // The flipbook shows exactly the PNG frames the run rendered, from the report's own folder.
  std::set<std::string> shown;
  for (const Json& record : data["frames"]) shown.insert(record["image"].get<std::string>());
  const std::set<std::string> rendered = filesIn(out / "png");
  ASSERT_EQ(rendered.size(), 12u);
  std::set<std::string> expected;
  for (const std::string& name : rendered) expected.insert("frames/" + name);
  EXPECT_EQ(shown, expected);
  EXPECT_EQ(filesIn(report / "frames"), rendered);
  for (const std::string& name : rendered)
    EXPECT_EQ(readFile(report / "frames" / name), readFile(out / "png" / name)) << name;

  // Nothing from the network: the SVG namespace is the only address, and it is a name.
  static const std::regex address(R"((https?|ftp)://[^\s"'<>)]+)");
  for (std::sregex_iterator it(html.begin(), html.end(), address), last; it != last; ++it)
    EXPECT_EQ(it->str(), "http://www.w3.org/2000/svg");
  EXPECT_EQ(html.find("src=\"/"), std::string::npos);
}

TEST_F(BakeReport, ARunThatBlowsUpStillWritesItsReportNamingTheFrame) {
  const fs::path out = folder_ / "out", report = folder_ / "report";
  // Explicit Euler far above its stability bound; each frame rendered as it is simulated, so the
  // frames before the blow-up have pictures.
  const test::Result run = runSoftbake(
      "run --integrator explicit --substeps 1 --frames 48 --render-while-simulating "
      "--size 64x36 -q --out " +
      quoted(out) + " --report " + quoted(report));
  ASSERT_EQ(run.exitCode, 2) << run.output;
  const Json manifest = Json::parse(readFile(out / "manifest.json"));
  std::smatch match;
  const std::string reason = manifest["reason"];
  ASSERT_TRUE(std::regex_search(reason, match, std::regex("blew up at frame (\\d+)"))) << reason;
  const int failed = std::stoi(match[1]);
  ASSERT_GE(failed, 3) << "the report needs frames before the blow-up to show";

  const std::string html = readFile(report / "index.html");
  const Json data = reportData(html);
  ASSERT_TRUE(data.is_object()) << html.substr(0, 2000);
  EXPECT_NE(html.find("id=\"headline\">blew up at frame " + std::to_string(failed)),
            std::string::npos);
  EXPECT_EQ(data["failed_frame"], failed);
  // Every frame simulated before it, and no other.
  ASSERT_EQ(data["frames"].size(), std::size_t(failed - 1));
  for (int f = 1; f < failed; ++f) EXPECT_EQ(data["frames"][f - 1]["frame"], f);
  EXPECT_EQ(lineCount(out / "frame_stats.jsonl"), std::size_t(failed - 1));
  // The flagged frames name it with the error, and every plot marks it.
  const std::string flagged = element(html, "flagged", "table");
  EXPECT_NE(flagged.find("<tr class=\"failed\" data-frame=\"" + std::to_string(failed) + "\""),
            std::string::npos)
      << flagged;
  EXPECT_NE(flagged.find("blew up at frame " + std::to_string(failed)), std::string::npos);
  for (const char* plot :
       {"plot-substeps", "plot-contacts", "plot-energy", "plot-volume", "plot-step-time"})
    EXPECT_NE(element(html, plot, "figure").find("class=\"mark\""), std::string::npos) << plot;
  // The energy grew before it blew up: the frame before is flagged for it.
  const Json& before = data["frames"][failed - 2];
  EXPECT_TRUE(std::any_of(before["problems"].begin(), before["problems"].end(),
                          [](const Json& problem) {
                            return problem.get<std::string>().find("energy rose") !=
                                   std::string::npos;
                          }))
      << before;
  // The flipbook has the frames that were rendered, exactly.
  std::set<std::string> shown, rendered;
  for (const Json& record : data["frames"])
    if (!record["image"].is_null()) shown.insert(record["image"].get<std::string>());
  for (const std::string& name : filesIn(out / "png"))
    if (fs::path(name).extension() == ".png") rendered.insert("frames/" + name);
  EXPECT_EQ(rendered.size(), std::size_t(failed - 1));
  EXPECT_EQ(shown, rendered);
}

TEST_F(BakeReport, AResumedRunReportsTheFramesAnEarlierInvocationSimulated) {
  const std::string options = " --frames 24 --checkpoint-every 4 --no-render -q";
  const fs::path out = folder_ / "out", report = folder_ / "report";
  const std::string command =
      "run" + options + " --out " + quoted(out) + " --report " + quoted(report);
  ASSERT_EQ(runSoftbake(command).exitCode, 0);
  const std::string first = readFile(out / "frame_stats.jsonl");
  // A lost frame: --resume restores the checkpoint of frame 17 and simulates 18 to 24 again.
  fs::remove(out / "obj/default_0020.obj");
  const test::Result resumed = runSoftbake(command + " --resume");
  ASSERT_EQ(resumed.exitCode, 0) << resumed.output;
  ASSERT_NE(resumed.output.find("from the checkpoint of frame 17"), std::string::npos)
      << resumed.output;
  const Json data = reportData(readFile(report / "index.html"));
  ASSERT_EQ(data["frames"].size(), 24u);
  std::istringstream firstLines(first);
  std::string line;
  for (int f = 1; std::getline(firstLines, line); ++f) {
    const Json record = Json::parse(line);
    const Json& now = data["frames"][f - 1];
    ASSERT_EQ(now["frame"], f);
    // The same run, simulated again where it was: the same numbers to the last bit.
    EXPECT_EQ(now["kinetic_energy"], record["kinetic_energy"]) << f;
    EXPECT_EQ(now["volumes"], record["volumes"]) << f;
    // Frames up to the checkpoint are the first invocation's records, times included.
    if (f <= 17) {
      EXPECT_EQ(now["step_ms"], record["step_ms"]) << f;
    }
  }
  EXPECT_EQ(readFile(report / "index.html").find("not recorded"), std::string::npos);

  // A run made without --report: the resumed one reports the frames it has, and says which it
  // lacks.
  const fs::path bare = folder_ / "bare", bareReport = folder_ / "bare_report";
  ASSERT_EQ(runSoftbake("run" + options + " --out " + quoted(bare)).exitCode, 0);
  fs::remove(bare / "obj/default_0020.obj");
  ASSERT_EQ(runSoftbake("run" + options + " --out " + quoted(bare) + " --report " +
                        quoted(bareReport) + " --resume")
                .exitCode,
            0);
  const std::string html = readFile(bareReport / "index.html");
  EXPECT_EQ(reportData(html)["frames"].size(), 8u);  // 17, restored, and 18 to 24
  EXPECT_NE(html.find("<tr><td>not recorded</td><td>frames 1–16: simulated by an earlier "
                      "invocation of the run without --report</td></tr>"),
            std::string::npos)
      << element(html, "summary", "table");
}

TEST_F(BakeReport, TheReportOpensOfflineInChromiumWithItsFlipbookAndPlots) {
  const fs::path out = folder_ / "out", report = folder_ / "report";
  const test::Result run = runSoftbake("run --frames 8 --size 96x54 -q --out " + quoted(out) +
                                       " --report " + quoted(report));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  // Moved elsewhere, as CI's artifacts are, and the run's folder gone: the report holds all it
  // shows.
  const fs::path moved = folder_ / "artifacts/report";
  fs::create_directories(moved.parent_path());
  fs::rename(report, moved);
  fs::remove_all(out);
  const fs::path screenshot = fs::path(SOFTBAKE_TEST_ARTIFACTS_DIR) / "bake_report.png";
  const test::Result check = checkReport("bake " + quoted(moved) + " 8 " + quoted(screenshot));
  EXPECT_EQ(check.exitCode, 0) << check.output;
  EXPECT_GT(fs::file_size(screenshot), 1000u);
}

}  // namespace

/// A balloon follows the gas law by design (bulk_modulus 0): it stays 40% above its rest volume
/// and is plotted, not flagged. A rubber ball pumped to 20 kPa keeps its bulk modulus and stays
/// 34% above rest: flagged on every frame, in one row for the frames flagged alike.
TEST_F(BakeReport, OnlyBodiesThatKeepTheirVolumeAreFlaggedAndAlikeFramesShareARow) {
  const fs::path scene = writeScene("inflated.json", R"({"settings": {"frames": 12}, "bodies": [
    {"name": "balloon", "mesh": {"primitive": "icosphere"}, "transform": {"translate": [-0.7, 1, 0]},
     "material": "balloon"},
    {"name": "pumped", "mesh": {"primitive": "icosphere"}, "transform": {"translate": [0.7, 1, 0]},
     "material": {"preset": "rubber", "pressure": 20000}}],
    "colliders": [{"type": "plane", "name": "ground"}]})");
  const fs::path out = folder_ / "out", report = folder_ / "report";
  const test::Result run = runSoftbake("run " + quoted(scene) + " --no-render -q --out " +
                                       quoted(out) + " --report " + quoted(report));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const std::string html = readFile(report / "index.html");
  const Json data = reportData(html);
  ASSERT_EQ(data["frames"].size(), 12u);
  for (std::size_t f = 1; f < 12; ++f) {
    const Json& frame = data["frames"][f];
    EXPECT_GT(frame["volumes"][0].get<double>(),
              1.1 * data["bodies"][0]["rest_volume"].get<double>())
        << "the balloon inflates, frame " << f + 1;
    ASSERT_EQ(frame["problems"].size(), 1u) << frame.dump();
    EXPECT_NE(frame["problems"][0].get<std::string>().find("'pumped'"), std::string::npos);
  }
  const std::string flagged = element(html, "flagged", "table");
  std::size_t rows = 0;
  for (std::size_t at = flagged.find("<tr class=\"flagged\""); at != std::string::npos;
       at = flagged.find("<tr class=\"flagged\"", at + 1))
    ++rows;
  EXPECT_EQ(rows, 1u) << flagged;
  EXPECT_NE(flagged.find("frames 2–12"), std::string::npos) << flagged;
}

}  // namespace softbake
