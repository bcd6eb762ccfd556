// The cache writer's files, and what a resume reads back from them: frame and checkpoint records
// at their documented names, the index, the latest whole checkpoint with damaged ones passed over,
// and the checkpoint interval that keeps checkpoints within a tenth of the cache.
#include "output/cache_writer.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "output/file_digest.hpp"
#include "tests/support/scratch_directory.hpp"

namespace softbake {
namespace {

using test::listDirectory;
using test::readFile;
using test::ScratchDirectory;

Frame frameNumber(int number, std::size_t particles) {
  Frame frame;
  frame.number = number;
  frame.time = (number - 1) / 24.0;
  for (std::size_t i = 0; i < particles; ++i) {
    frame.positions.push_back(Vec3(Scalar(i), Scalar(number), 0.5f));
    frame.velocities.push_back(Vec3(0, -Scalar(number), Scalar(i)));
  }
  return frame;
}

SimulationCheckpoint checkpointAt(int number, std::size_t particles) {
  SimulationCheckpoint checkpoint;
  const Frame frame = frameNumber(number, particles);
  checkpoint.state.position = frame.positions;
  checkpoint.state.velocity = frame.velocities;
  checkpoint.stepsTaken = std::uint64_t(number) * 10;
  return checkpoint;
}

/// Frames 1…`frames` through a CacheWriter, a checkpoint every `every`.
void writeCache(const std::filesystem::path& out, int frames, int every) {
  CacheWriter writer(out, "shot", 4, frames, every, 3);
  for (int number = 1; number <= frames; ++number) {
    Frame frame = frameNumber(number, 3);
    frame.hasCheckpoint = isCheckpointFrame(number, every);
    if (frame.hasCheckpoint) frame.checkpoint = checkpointAt(number, 3);
    writer.write(frame);
  }
  writer.finish();
}

TEST(CacheWriter, WritesEveryFrameACheckpointEveryNAndTheIndex) {
  ScratchDirectory dir;
  writeCache(dir.path(), 10, 4);
  EXPECT_EQ(listDirectory(dir.path() / "cache"),
            (std::vector<std::string>{
                "index.json", "shot_0001.sbframe", "shot_0002.sbframe", "shot_0003.sbframe",
                "shot_0004.sbframe", "shot_0005.sbcheckpoint", "shot_0005.sbframe",
                "shot_0006.sbframe", "shot_0007.sbframe", "shot_0008.sbframe",
                "shot_0009.sbcheckpoint", "shot_0009.sbframe", "shot_0010.sbframe"}));
  const nlohmann::json index = nlohmann::json::parse(readFile(dir.path() / "cache/index.json"));
  EXPECT_EQ(index["checkpoints"], nlohmann::json::array({5, 9}));
  EXPECT_EQ(index["last_frame"], 10);
  EXPECT_EQ(index["particles"], 3);
  EXPECT_EQ(index["frame_pattern"], "cache/shot_####.sbframe");

  const CacheLayout layout(dir.path(), "shot", 4);
  Frame back;
  layout.readFrame(7, back);
  const Frame expected = frameNumber(7, 3);
  EXPECT_EQ(back.number, 7);
  EXPECT_EQ(back.positions, expected.positions);
  EXPECT_EQ(back.velocities, expected.velocities);
  EXPECT_THROW(layout.readFrame(11, back), Error);
}

TEST(CacheWriter, TheLatestWholeCheckpointAtOrBeforeAFrame) {
  ScratchDirectory dir;
  writeCache(dir.path(), 20, 4);
  const CacheLayout layout(dir.path(), "shot", 4);
  EXPECT_FALSE(layout.latestCheckpoint(4, nullptr));  // none before frame 5
  EXPECT_EQ(layout.latestCheckpoint(5, nullptr)->frame, 5);
  EXPECT_EQ(layout.latestCheckpoint(16, nullptr)->frame, 13);
  const std::optional<DecodedCheckpoint> latest = layout.latestCheckpoint(20, nullptr);
  ASSERT_TRUE(latest);
  EXPECT_EQ(latest->frame, 17);
  EXPECT_EQ(latest->checkpoint.stepsTaken, 170u);
  EXPECT_EQ(latest->checkpoint.state.position, checkpointAt(17, 3).state.position);

  // A flipped byte in checkpoint 17, and checkpoint 13 cut short: 9 it is, with both named.
  const std::filesystem::path seventeen = layout.checkpointPath(17);
  std::string bytes = readFile(seventeen);
  bytes[70] ^= 0x04;
  std::ofstream(seventeen, std::ios::binary) << bytes;
  const std::string thirteen = readFile(layout.checkpointPath(13));
  std::ofstream(layout.checkpointPath(13), std::ios::binary) << thirteen.substr(0, 100);
  std::vector<std::string> skipped;
  EXPECT_EQ(layout.latestCheckpoint(20, &skipped)->frame, 9);
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_NE(skipped[0].find("shot_0017.sbcheckpoint: the cache file's data does not match"),
            std::string::npos)
      << skipped[0];
  EXPECT_NE(skipped[1].find("shot_0013.sbcheckpoint"), std::string::npos) << skipped[1];
}

TEST(CacheWriter, ACheckpointUnderAnotherFramesNameIsNotTaken) {
  ScratchDirectory dir;
  writeCache(dir.path(), 10, 4);
  const CacheLayout layout(dir.path(), "shot", 4);
  std::filesystem::copy_file(layout.checkpointPath(5), layout.checkpointPath(9),
                             std::filesystem::copy_options::overwrite_existing);
  std::vector<std::string> skipped;
  EXPECT_EQ(layout.latestCheckpoint(10, &skipped)->frame, 5);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_NE(skipped[0].find("holds frame 5"), std::string::npos) << skipped[0];
}

TEST(CacheWriter, CheckpointsEveryNFramesAfterTheFirst) {
  EXPECT_FALSE(isCheckpointFrame(1, 4));
  EXPECT_TRUE(isCheckpointFrame(5, 4));
  EXPECT_FALSE(isCheckpointFrame(6, 4));
  EXPECT_TRUE(isCheckpointFrame(2, 1));
  EXPECT_FALSE(isCheckpointFrame(5, 0));  // no cache
  // Within a tenth of the cache: a checkpoint 1.6 frames large, every 16 frames, is exactly 10%.
  EXPECT_EQ(defaultCheckpointInterval(160, 100), 16);
  EXPECT_EQ(defaultCheckpointInterval(161, 100), 17);
  EXPECT_EQ(defaultCheckpointInterval(1, 1000), 1);
  for (const auto& [checkpoint, frame] :
       {std::pair<std::size_t, std::size_t>{50'000, 31'000}, {1'000'000, 240'000}}) {
    const int every = defaultCheckpointInterval(checkpoint, frame);
    EXPECT_LE(double(checkpoint) / (double(every) * double(frame)), 0.1);
    EXPECT_GT(double(checkpoint) / (double(every - 1) * double(frame)), 0.1);
  }
}

TEST(FileDigest, IsTheSha256OfTheBytes) {
  // FIPS 180-2's examples: "abc" and the empty message.
  ScratchDirectory dir;
  std::ofstream(dir.path() / "abc") << "abc";
  EXPECT_EQ(sha256OfFile(dir.path() / "abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  std::ofstream(dir.path() / "empty") << "";
  EXPECT_EQ(sha256OfFile(dir.path() / "empty"),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256("abc").size(), 32u);
  EXPECT_EQ(std::uint8_t(sha256("abc")[0]), 0xbau);
  EXPECT_THROW(sha256OfFile(dir.path() / "missing"), Error);
}

}  // namespace
}  // namespace softbake
