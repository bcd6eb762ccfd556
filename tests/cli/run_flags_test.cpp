// `softbake run` flags, each checked by what it changes in the files or the output, not only by
// the exit status: --fps, --frame-padding, --levels, --response, --vdb-fog, --vdb-compression,
// --no-contact-spheres, --contacts-view (with export's), --no-self-collision, and the progress
// lines of a run that is not --quiet.
#include <gtest/gtest.h>

#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <Eigen/Core>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
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

fs::path example(const std::string& name) {
  return fs::path(SOFTBAKE_SOURCE_DIR) / "examples" / (name + ".json");
}

/// Each `o` block's vertex average, in file order.
std::vector<Eigen::Vector3d> objectCentroids(const std::string& obj) {
  std::vector<Eigen::Vector3d> sums;
  std::vector<int> counts;
  std::istringstream lines(obj);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("o ", 0) == 0) {
      sums.push_back(Eigen::Vector3d::Zero());
      counts.push_back(0);
    } else if (line.rfind("v ", 0) == 0 && !sums.empty()) {
      Eigen::Vector3d p;
      std::sscanf(line.c_str() + 2, "%lf %lf %lf", &p.x(), &p.y(), &p.z());
      sums.back() += p;
      ++counts.back();
    }
  }
  for (std::size_t i = 0; i < sums.size(); ++i) sums[i] /= std::max(counts[i], 1);
  return sums;
}

nlohmann::json readJson(const fs::path& path) {
  return nlohmann::json::parse(readFile(path));
}

class RunFlags : public CliTest {};

TEST_F(RunFlags, FpsSetsTheFramesTimesAndTheSimulatedTime) {
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run " + quoted(example("fig5_ground")) +
                                 " --fps 10 --frames 3 --no-render -q -o " + quoted(out));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_EQ(readJson(out / "manifest.json").at("fps").get<double>(), 10.0);
  const std::string frame3 = readFile(out / "obj/fig5_ground_0003.obj");
  EXPECT_NE(frame3.find("\n# frame 3, time 0.2 s\n"), std::string::npos) << frame3.substr(0, 80);
  // The ball flies at 0.5 m/s sideways with nothing pushing it that way: 0.2 s of it is 0.1 m,
  // where 24 fps would have given 2/24 s and 0.042 m.
  const std::vector<Eigen::Vector3d> centroids = objectCentroids(frame3);
  ASSERT_EQ(centroids.size(), 1u);
  EXPECT_NEAR(centroids[0].x(), 0.5 * 0.2, 1e-5);
}

TEST_F(RunFlags, FramePaddingSetsTheDigitsOfEveryFileName) {
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake(
      "run --frames 2 --frame-padding 6 --contacts --vdb --no-render "
      "-q -o " +
      quoted(out));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  for (const char* file : {"obj/default_000001.obj", "obj/default_000002.obj",
                           "contacts/default_000002.json", "vdb/default_000002.vdb"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  EXPECT_FALSE(fs::exists(out / "obj/default_0002.obj"));
  const nlohmann::json manifest = readJson(out / "manifest.json");
  EXPECT_EQ(manifest.at("frame_padding").get<int>(), 6);
  std::vector<std::string> patterns;
  for (const nlohmann::json& sequence : manifest.at("sequences"))
    patterns.push_back(sequence.at("printf_pattern").get<std::string>());
  EXPECT_EQ(patterns,
            (std::vector<std::string>{"obj/default_%06d.obj", "contacts/default_%06d.json",
                                      "vdb/default_%06d.vdb", "cache/default_%06d.sbframe"}));
  EXPECT_TRUE(fs::exists(out / "cache/default_000002.sbframe"));
  const Result bad = runSoftbake("run --frame-padding 10 -o " + quoted(folder_ / "bad"));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
}

// flag_fold's flag without its own self_collision key, so the scene's setting decides: the flag
// folds onto itself from frame 18.
fs::path flagScene(const fs::path& folder, const std::string& collisions) {
  nlohmann::json scene = readJson(example("flag_fold"));
  scene["bodies"][0]["mesh"] = (fs::path(SOFTBAKE_SOURCE_DIR) / "examples/sheet_24.obj").string();
  scene["bodies"][0].erase("self_collision");
  scene["settings"]["frames"] = 24;
  if (!collisions.empty()) scene["settings"]["collisions"] = nlohmann::json::parse(collisions);
  const fs::path path = folder / ("flag" + std::to_string(collisions.size()) + ".json");
  std::ofstream(path) << scene.dump();
  return path;
}

// Contacts of a body with itself, over every frame's contacts file.
int selfContacts(const fs::path& out) {
  int count = 0;
  for (int frame = 1; frame <= 24; ++frame) {
    char name[64];
    std::snprintf(name, sizeof name, "contacts/flag_fold_%04d.json", frame);
    const nlohmann::json contacts = readJson(out / name);
    for (const nlohmann::json& contact : contacts.at("contacts"))
      count += contact.at("bodies")[0] == contact.at("bodies")[1];
  }
  return count;
}

TEST_F(RunFlags, NoSelfCollisionLetsAFoldingFlagPassItselfAsTheSceneKeyDoes) {
  const auto bake = [&](const fs::path& scene, const std::string& flags, const char* name) {
    const fs::path out = folder_ / name;
    const Result run = runSoftbake("run " + quoted(scene) + " --contacts --no-render --no-cache " +
                                   flags + " -q -o " + quoted(out));
    EXPECT_EQ(run.exitCode, 0) << run.output;
    return out;
  };
  const fs::path plain = flagScene(folder_, "");
  const fs::path byDefault = bake(plain, "", "default");
  const fs::path byFlag = bake(plain, "--no-self-collision", "flag");
  const fs::path byKey = bake(flagScene(folder_, R"({"self_collision": false})"), "", "key");
  EXPECT_GT(selfContacts(byDefault), 20);
  EXPECT_EQ(selfContacts(byFlag), 0);
  // The flag lands where the scene key lands: the same bytes.
  EXPECT_EQ(readFile(byFlag / "obj/flag_fold_0024.obj"),
            readFile(byKey / "obj/flag_fold_0024.obj"));
  EXPECT_NE(readFile(byFlag / "obj/flag_fold_0024.obj"),
            readFile(byDefault / "obj/flag_fold_0024.obj"));
  EXPECT_TRUE(
      readJson(byFlag / "manifest.json")["run"]["options"]["no-self-collision"].get<bool>());
  // bench takes it too: no pairs of the flag with itself to look at.
  const Result bench = runSoftbake("bench " + quoted(plain) + " --frames 20 --no-self-collision");
  ASSERT_EQ(bench.exitCode, 0) << bench.output;
  EXPECT_NE(bench.output.find(" contacts_per_step=0.0 "), std::string::npos) << bench.output;
}

TEST_F(RunFlags, LevelsReachTheSbhashBroadPhaseAndChangeNoResult) {
  // fig4's bodies touch within 20 frames, so the broad phase has pairs to find at every level.
  std::string reference;
  for (int levels : {0, 1, 5}) {
    const fs::path out = folder_ / std::to_string(levels);
    const Result run = runSoftbake("run " + quoted(example("fig4_two_bodies")) +
                                   " --frames 20 --broadphase sbhash --levels " +
                                   std::to_string(levels) + " --no-render -o " + quoted(out));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find("collisions: sbhash broad phase (level " + std::to_string(levels) +
                              "), two-sided response"),
              std::string::npos)
        << run.output;
    const std::string frame = readFile(out / "obj/fig4_two_bodies_0020.obj");
    ASSERT_FALSE(frame.empty());
    if (reference.empty()) reference = frame;
    EXPECT_TRUE(frame == reference) << "level " << levels << " changed the simulation";
  }
  const Result bad = runSoftbake("run --levels 9 -o " + quoted(folder_ / "bad"));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
}

TEST_F(RunFlags, ResponseNoneLetsTheBallsPassThroughEachOtherAndPaperDiffers) {
  // The built-in scene throws ballA from x = -1.2 rightwards and ballB from x = 1.2 leftwards;
  // they meet by frame 14. At frame 20 (0.79 s) unhindered they would be at about x = ±0.78.
  std::string twoSided;
  std::vector<Eigen::Vector3d> centroids;
  for (const char* response : {"two-sided", "paper", "none"}) {
    const fs::path out = folder_ / response;
    const Result run = runSoftbake(std::string("run --frames 20 --no-render --response ") +
                                   response + " -o " + quoted(out));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    const std::string frame = readFile(out / "obj/default_0020.obj");
    centroids = objectCentroids(frame);
    ASSERT_EQ(centroids.size(), 2u);
    if (std::string(response) == "two-sided") {
      twoSided = frame;
      EXPECT_LT(centroids[0].x(), centroids[1].x()) << "the balls bounced apart";
      EXPECT_NE(run.output.find(", two-sided response"), std::string::npos) << run.output;
      // The default is two-sided.
      const Result byDefault =
          runSoftbake("run --frames 20 --no-render -q -o " + quoted(folder_ / "default"));
      ASSERT_EQ(byDefault.exitCode, 0) << byDefault.output;
      EXPECT_TRUE(readFile(folder_ / "default/obj/default_0020.obj") == frame);
    } else if (std::string(response) == "paper") {
      EXPECT_LT(centroids[0].x(), centroids[1].x()) << "the balls bounced apart";
      EXPECT_NE(run.output.find(", paper response"), std::string::npos) << run.output;
      EXPECT_FALSE(frame == twoSided) << "paper moves only the particle, two-sided both sides";
    } else {
      EXPECT_NE(run.output.find(", detection only (response \"none\")"), std::string::npos)
          << run.output;
      EXPECT_GT(centroids[0].x(), 0.5) << "ballA went on through ballB";
      EXPECT_LT(centroids[1].x(), -0.5) << "ballB went on through ballA";
    }
  }
  const Result bad = runSoftbake("run --response bounce -o " + quoted(folder_ / "bad"));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
}

/// The grids of a VDB file, read back by OpenVDB.
openvdb::GridPtrVecPtr readGrids(const fs::path& path) {
  openvdb::initialize();
  openvdb::io::File file(path.string());
  file.open();
  openvdb::GridPtrVecPtr grids = file.getGrids();
  file.close();
  return grids;
}

openvdb::FloatGrid::Ptr floatGrid(const openvdb::GridPtrVecPtr& grids, const std::string& name) {
  for (const openvdb::GridBase::Ptr& grid : *grids)
    if (grid->getName() == name) return openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
  return nullptr;
}

TEST_F(RunFlags, VdbFogAddsADensityGridPerBody) {
  for (const bool fog : {false, true}) {
    const fs::path out = folder_ / (fog ? "fog" : "plain");
    const Result run = runSoftbake(std::string("run --vdb --no-render --frames 1 -q") +
                                   (fog ? " --vdb-fog" : "") + " -o " + quoted(out));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    const openvdb::GridPtrVecPtr grids = readGrids(out / "vdb/default_0001.vdb");
    for (const char* body : {"ballA", "ballB"}) {
      const std::string name = std::string(body) + "_density";
      const openvdb::FloatGrid::Ptr density = floatGrid(grids, name);
      EXPECT_EQ(bool(density), fog) << name;
      if (!density) continue;
      EXPECT_EQ(density->getGridClass(), openvdb::GRID_FOG_VOLUME);
      // Fog is 1 deep inside the body and 0 outside it.
      EXPECT_EQ(density->background(), 0.0f) << name;
      float highest = 0;
      for (auto v = density->cbeginValueOn(); v; ++v) highest = std::max(highest, *v);
      EXPECT_EQ(highest, 1.0f) << name;
    }
  }
}

TEST_F(RunFlags, VdbCompressionShrinksTheFilesAndKeepsEveryVoxel) {
  std::uintmax_t sizes[3] = {};
  openvdb::FloatGrid::Ptr surfaces[3];
  const char* kinds[3] = {"none", "zip", "blosc"};
  for (int k = 0; k < 3; ++k) {
    const fs::path out = folder_ / kinds[k];
    const Result run = runSoftbake(std::string("run --vdb --no-render --frames 1 -q ") +
                                   "--vdb-compression " + kinds[k] + " -o " + quoted(out));
    ASSERT_EQ(run.exitCode, 0) << kinds[k] << ": " << run.output;
    sizes[k] = fs::file_size(out / "vdb/default_0001.vdb");
    surfaces[k] = floatGrid(readGrids(out / "vdb/default_0001.vdb"), "ballA_surface");
    ASSERT_TRUE(surfaces[k]) << kinds[k];
  }
  EXPECT_LT(sizes[1], sizes[0] * 9 / 10) << "zip";
  EXPECT_LT(sizes[2], sizes[0] * 9 / 10) << "blosc";
  for (int k = 1; k < 3; ++k) {
    EXPECT_EQ(surfaces[k]->activeVoxelCount(), surfaces[0]->activeVoxelCount()) << kinds[k];
    const auto reference = surfaces[0]->getConstAccessor();
    for (auto v = surfaces[k]->cbeginValueOn(); v; ++v)
      ASSERT_EQ(*v, reference.getValue(v.getCoord())) << kinds[k] << " at " << v.getCoord();
  }
  const Result bad = runSoftbake("run --vdb --vdb-compression lzma -o " + quoted(folder_ / "bad"));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
}

struct Image {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
};

Image decodePng(const fs::path& path) {
  const std::string png = readFile(path);
  Image image;
  int channels = 0;
  unsigned char* data =
      stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()), int(png.size()),
                            &image.width, &image.height, &channels, 3);
  if (data) image.rgb.assign(data, data + std::size_t(image.width * image.height) * 3);
  stbi_image_free(data);
  return image;
}

/// How far a pixel is towards the contact colour (a saturated red): red less the larger of green
/// and blue.
int redness(const unsigned char* p) {
  return int(p[0]) - int(std::max(p[1], p[2]));
}

TEST_F(RunFlags, NoContactSpheresRemovesTheSpheresAndNothingElse) {
  constexpr int kFrames = 14, kWidth = 320, kHeight = 240;  // the balls meet by frame 14
  // The view held, so only the spheres differ: without them the default view would be opaque.
  for (const bool spheres : {true, false}) {
    const Result run =
        runSoftbake("run --render --contacts -q --size " + std::to_string(kWidth) + "x" +
                    std::to_string(kHeight) + " --frames " + std::to_string(kFrames) +
                    (spheres ? "" : " --no-contact-spheres --contacts-view xray") + " -o " +
                    quoted(folder_ / (spheres ? "on" : "off")));
    ASSERT_EQ(run.exitCode, 0) << run.output;
  }
  int framesWithContacts = 0, framesWithVisibleSpheres = 0;
  long rednessWith = 0, rednessWithout = 0;
  for (int frame = 1; frame <= kFrames; ++frame) {
    char name[32];
    std::snprintf(name, sizeof name, "default_%04d", frame);
    const std::size_t contacts =
        readJson(folder_ / "on/contacts" / (std::string(name) + ".json")).at("contacts").size();
    const Image with = decodePng(folder_ / "on/png" / (std::string(name) + ".png"));
    const Image without = decodePng(folder_ / "off/png" / (std::string(name) + ".png"));
    ASSERT_EQ(with.rgb.size(), std::size_t(kWidth * kHeight * 3)) << name;
    ASSERT_EQ(without.rgb.size(), with.rgb.size()) << name;
    if (contacts == 0) {
      EXPECT_TRUE(with.rgb == without.rgb) << name << " has no contacts, so no spheres";
      continue;
    }
    ++framesWithContacts;
    // The spheres are red (antialiased, a few pixels across, over translucent bodies): where the
    // images differ, the one with spheres is the redder.
    int changed = 0;
    long frameWith = 0, frameWithout = 0;
    for (std::size_t i = 0; i < with.rgb.size(); i += 3) {
      if (std::equal(&with.rgb[i], &with.rgb[i] + 3, &without.rgb[i])) continue;
      ++changed;
      frameWith += redness(&with.rgb[i]);
      frameWithout += redness(&without.rgb[i]);
    }
    // Plane contacts lie under a body; the others where the bodies press into each other. The
    // contact view shows them all.
    if (changed == 0) continue;
    ++framesWithVisibleSpheres;
    EXPECT_GT(frameWith, frameWithout) << name << ": the changed pixels did not turn redder";
    rednessWith += frameWith;
    rednessWithout += frameWithout;
  }
  EXPECT_GT(framesWithContacts, 0) << "the balls never met: the test shows nothing";
  EXPECT_EQ(framesWithVisibleSpheres, framesWithContacts)
      << "frames whose contacts drew no sphere in the contact view";
  EXPECT_GT(rednessWith, rednessWithout + 50L * framesWithContacts);
}

TEST_F(RunFlags, ContactsViewChoosesHowTheBodiesAreDrawnInRunSceneAndExport) {
  // The built-in scene: two balls that meet, so the contact view is the default.
  const auto render = [&](const std::string& name, const std::string& options) {
    const Result run = runSoftbake("run --render --size 160x120 --frames 13 -q -o " +
                                   quoted(folder_ / name) + " " + options);
    EXPECT_EQ(run.exitCode, 0) << run.output;
    return readFile(folder_ / name / "png/default_0013.png");
  };
  const std::string automatic = render("automatic", "");
  const std::string xray = render("xray", "--contacts-view xray");
  const std::string opaque = render("opaque", "--contacts-view opaque");
  ASSERT_FALSE(automatic.empty());
  EXPECT_TRUE(automatic == xray) << "two bodies that meet: the contact view by default";
  EXPECT_FALSE(xray == opaque);
  // Without spheres there is nothing to see through to: opaque by default.
  EXPECT_TRUE(render("bare", "--no-contact-spheres") ==
              render("bareOpaque", "--no-contact-spheres --contacts-view opaque"));

  // The scene's render.contacts_view, and the flag over it.
  nlohmann::json scene = nlohmann::json::parse(readFile(example("default")));
  const std::string fileXray = render("file", quoted(example("default")));
  const std::string fileOpaque =
      render("fileOpaque", quoted(example("default")) + " --contacts-view opaque");
  EXPECT_FALSE(fileXray == fileOpaque);
  scene["render"]["contacts_view"] = "opaque";
  const fs::path file = writeScene("default.json", scene.dump());
  EXPECT_TRUE(render("scene", quoted(file)) == fileOpaque);
  EXPECT_TRUE(render("sceneFlag", quoted(file) + " --contacts-view xray") == fileXray);

  // export renders the run's view, or the one it is given.
  const Result again = runSoftbake("export " + quoted(folder_ / "automatic") +
                                   " --png --frames 13 -q --contacts-view opaque");
  ASSERT_EQ(again.exitCode, 0) << again.output;
  EXPECT_TRUE(readFile(folder_ / "automatic/png/default_0013.png") == opaque);
  const Result back =
      runSoftbake("export " + quoted(folder_ / "automatic") + " --png --frames 13 -q");
  ASSERT_EQ(back.exitCode, 0) << back.output;
  EXPECT_TRUE(readFile(folder_ / "automatic/png/default_0013.png") == xray);

  const Result wrong = runSoftbake("run --contacts-view glass --frames 1 --no-render -o " +
                                   quoted(folder_ / "wrong"));
  EXPECT_EQ(wrong.exitCode, 1);
  EXPECT_NE(wrong.output.find("--contacts-view"), std::string::npos) << wrong.output;
}

TEST_F(RunFlags, WithoutQuietALogGetsAProgressLineEveryTenthOfTheRun) {
  const Result run = runSoftbake("run --frames 20 --no-render -o " + quoted(folder_ / "out"));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  std::vector<int> frames;
  std::istringstream lines(run.output);
  for (std::string line; std::getline(lines, line);) {
    int frame = 0, total = 0;
    if (std::sscanf(line.c_str(), "frame %d/%d ", &frame, &total) == 2 && total == 20)
      frames.push_back(frame);
  }
  EXPECT_EQ(frames, (std::vector<int>{1, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20})) << run.output;
  const Result quiet = runSoftbake("run --frames 20 --no-render -q -o " + quoted(folder_ / "q"));
  ASSERT_EQ(quiet.exitCode, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("frame 1/20"), std::string::npos) << quiet.output;
}

}  // namespace
}  // namespace softbake
