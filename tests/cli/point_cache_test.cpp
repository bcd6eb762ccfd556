// PC2 and MDD point caches through the binary, read back by a reader of this test's own written
// from the formats' published layouts (PC2 little-endian with its POINTCACHE2 header, MDD
// big-endian with frame times first): frame N of each body equals the OBJ sequence's frame N to
// float precision, in the same vertex order as the rest mesh; --up z turns them; written live
// (--no-cache) or from the cache after the simulation, the bytes are the same.
#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tests/cli/softbake_process.hpp"

namespace softbake::test {
namespace {

namespace fs = std::filesystem;

using Points = std::vector<std::array<float, 3>>;

template <class T>
T little(const std::string& bytes, std::size_t at) {
  T value;
  std::memcpy(&value, bytes.data() + at, sizeof value);
  return value;
}

template <class T>
T big(const std::string& bytes, std::size_t at) {
  std::uint32_t raw = 0;
  for (int i = 0; i < 4; ++i) raw = raw << 8 | std::uint8_t(bytes[at + std::size_t(i)]);
  return std::bit_cast<T>(raw);
}

struct PointCache {
  int points = 0, frames = 0;
  float startFrame = 0, sampleRate = 0;
  std::vector<float> times;
  std::vector<Points> positions;  ///< [frame − 1][point]
};

PointCache readPc2(const std::string& bytes) {
  PointCache cache;
  EXPECT_EQ(bytes.substr(0, 12), std::string("POINTCACHE2\0", 12));
  EXPECT_EQ(little<std::int32_t>(bytes, 12), 1);  // version
  cache.points = little<std::int32_t>(bytes, 16);
  cache.startFrame = little<float>(bytes, 20);
  cache.sampleRate = little<float>(bytes, 24);
  cache.frames = little<std::int32_t>(bytes, 28);
  EXPECT_EQ(bytes.size(), 32u + std::size_t(cache.frames) * std::size_t(cache.points) * 12);
  for (int f = 0; f < cache.frames; ++f) {
    Points frame(std::size_t(cache.points));
    for (int p = 0; p < cache.points; ++p)
      for (int k = 0; k < 3; ++k)
        frame[std::size_t(p)][std::size_t(k)] = little<float>(
            bytes, 32 + (std::size_t(f) * std::size_t(cache.points) + std::size_t(p)) * 12 +
                       std::size_t(k) * 4);
    cache.positions.push_back(frame);
  }
  return cache;
}

PointCache readMdd(const std::string& bytes) {
  PointCache cache;
  cache.frames = big<std::int32_t>(bytes, 0);
  cache.points = big<std::int32_t>(bytes, 4);
  for (int f = 0; f < cache.frames; ++f)
    cache.times.push_back(big<float>(bytes, 8 + 4 * std::size_t(f)));
  const std::size_t data = 8 + 4 * std::size_t(cache.frames);
  EXPECT_EQ(bytes.size(), data + std::size_t(cache.frames) * std::size_t(cache.points) * 12);
  for (int f = 0; f < cache.frames; ++f) {
    Points frame(std::size_t(cache.points));
    for (int p = 0; p < cache.points; ++p)
      for (int k = 0; k < 3; ++k)
        frame[std::size_t(p)][std::size_t(k)] = big<float>(
            bytes, data + (std::size_t(f) * std::size_t(cache.points) + std::size_t(p)) * 12 +
                       std::size_t(k) * 4);
    cache.positions.push_back(frame);
  }
  return cache;
}

/// The `v` lines of each `o` block of an OBJ file, as float32 (the OBJ holds shortest-form floats).
std::vector<Points> objBodies(const fs::path& path) {
  std::vector<Points> bodies;
  std::istringstream in(readFile(path));
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("o ", 0) == 0) bodies.emplace_back();
    if (line.rfind("v ", 0) != 0) continue;
    std::istringstream numbers(line.substr(2));
    std::array<float, 3> p{};
    for (float& x : p) {
      double value = 0;
      numbers >> value;
      x = float(value);
    }
    bodies.back().push_back(p);
  }
  return bodies;
}

class PointCaches : public CliTest {};

TEST_F(PointCaches, EveryFrameEqualsTheObjSequenceInTheRestMeshsOrder) {
  const fs::path out = folder_ / "out";
  const Result run = runSoftbake("run --frames 24 --no-render --pc2 --mdd -q -o " + quoted(out));
  ASSERT_EQ(run.exitCode, 0) << run.output;
  const nlohmann::json manifest = nlohmann::json::parse(readFile(out / "manifest.json"));
  ASSERT_EQ(manifest["point_caches"].size(), 2u);
  for (std::size_t b = 0; b < 2; ++b) {
    const nlohmann::json& entry = manifest["point_caches"][b];
    SCOPED_TRACE(entry.dump());
    const PointCache pc2 = readPc2(readFile(out / entry["pc2"].get<std::string>()));
    const PointCache mdd = readMdd(readFile(out / entry["mdd"].get<std::string>()));
    EXPECT_EQ(pc2.frames, 24);
    EXPECT_EQ(pc2.startFrame, 1.0f);
    EXPECT_EQ(pc2.sampleRate, 1.0f);
    EXPECT_EQ(mdd.frames, 24);
    EXPECT_EQ(mdd.points, pc2.points);
    EXPECT_EQ(mdd.times[0], 0.0f);
    EXPECT_FLOAT_EQ(mdd.times[23], 23.0f / 24.0f);
    for (int frame : {1, 2, 13, 24}) {
      char name[32];
      std::snprintf(name, sizeof name, "obj/default_%04d.obj", frame);
      const Points obj = objBodies(out / name)[b];
      ASSERT_EQ(obj.size(), std::size_t(pc2.points));
      EXPECT_TRUE(pc2.positions[std::size_t(frame - 1)] == obj) << "PC2 frame " << frame;
      EXPECT_TRUE(mdd.positions[std::size_t(frame - 1)] == obj) << "MDD frame " << frame;
    }
    // The rest mesh's vertices are frame 1's, in the same order.
    EXPECT_TRUE(objBodies(out / entry["mesh"].get<std::string>())[0] == pc2.positions[0]);
  }
}

TEST_F(PointCaches, UpZTurnsTheCachesAndTheRestMeshes) {
  const fs::path y = folder_ / "y", z = folder_ / "z";
  ASSERT_EQ(runSoftbake("run --frames 6 --no-render --pc2 -q -o " + quoted(y)).exitCode, 0);
  ASSERT_EQ(runSoftbake("run --frames 6 --no-render --pc2 --up z -q -o " + quoted(z)).exitCode, 0);
  const PointCache up = readPc2(readFile(y / "pc2/default_ballA.pc2"));
  const PointCache turned = readPc2(readFile(z / "pc2/default_ballA.pc2"));
  for (std::size_t p = 0; p < up.positions[5].size(); ++p) {
    const auto& a = up.positions[5][p];
    const auto& b = turned.positions[5][p];
    EXPECT_EQ(b[0], a[0]);
    EXPECT_EQ(b[1], -a[2]);
    EXPECT_EQ(b[2], a[1]);
  }
  EXPECT_TRUE(objBodies(z / "cache_mesh/default_ballA.obj")[0] == turned.positions[0]);
}

TEST_F(PointCaches, LiveAndFromTheCacheAndExportedAreTheSameBytes) {
  const fs::path live = folder_ / "live", cached = folder_ / "cached";
  ASSERT_EQ(runSoftbake("run --frames 12 --no-render --pc2 --mdd --no-cache -q -o " + quoted(live))
                .exitCode,
            0);
  ASSERT_EQ(runSoftbake("run --frames 12 --no-render -q -o " + quoted(cached)).exitCode, 0);
  EXPECT_FALSE(fs::exists(cached / "pc2"));
  const Result exported = runSoftbake("export " + quoted(cached) + " --pc2 --mdd -q");
  ASSERT_EQ(exported.exitCode, 0) << exported.output;
  for (const char* file : {"pc2/default_ballA.pc2", "pc2/default_ballB.pc2",
                           "mdd/default_ballB.mdd", "cache_mesh/default_ballB.obj"})
    EXPECT_TRUE(readFile(live / file) == readFile(cached / file)) << file;
  const Result partial = runSoftbake("export " + quoted(cached) + " --pc2 --frames 3:5");
  EXPECT_EQ(partial.exitCode, 1);
  EXPECT_NE(partial.output.find("point caches hold every frame"), std::string::npos)
      << partial.output;
}

}  // namespace
}  // namespace softbake::test
