// The simulation cache's bytes: records come back as they went in, the layout is the one
// cache_format.hpp documents (read here field by field at its offsets, as numpy would, with a
// CRC-32 of the test's own), and no damaged, cut or misplaced file is taken for a good one.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "core/error.hpp"
#include "output/cache_format.hpp"

namespace softbake {
namespace {

/// CRC-32 (IEEE 802.3, reflected, as zlib and Python's zlib.crc32), bit by bit.
std::uint32_t referenceCrc32(std::string_view bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char byte : bytes) {
    crc ^= std::uint8_t(byte);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

template <class T>
T at(const std::string& bytes, std::size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof value);
  return value;
}

Frame sampleFrame() {
  Frame frame;
  frame.number = 37;
  frame.time = 1.5;
  frame.positions = {Vec3(0.25f, -1, 3.5f), Vec3(1e-3f, 2, -7), Vec3(0, 0, 0)};
  frame.velocities = {Vec3(-0.5f, 4, 0), Vec3(9, 8, 7), Vec3(0, 0, 1e6f)};
  Contact edge;
  edge.position = Vec3(1, 2, 3);
  edge.normal = Vec3(0, 1, 0);
  edge.surfaceA = 0, edge.surfaceB = 1, edge.triangleA = 4, edge.triangleB = 9;
  Contact corner = edge;
  corner.kind = ContactKind::Corner;
  corner.triangleA = kNoIndex, corner.particle = 2;
  Contact plane = corner;
  plane.kind = ContactKind::Plane;
  plane.triangleB = kNoIndex, plane.surfaceB = 0, plane.particle = 1;
  frame.contacts = {edge, corner, plane};
  return frame;
}

TEST(CacheFrame, ComesBackAsItWentIn) {
  const Frame frame = sampleFrame();
  const Frame back = decodeCacheFrame(encodeCacheFrame(frame), "f.sbcache");
  EXPECT_EQ(back.number, 37);
  EXPECT_EQ(back.time, 1.5);
  ASSERT_EQ(back.positions.size(), 3u);
  ASSERT_EQ(back.velocities.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.positions[i], frame.positions[i]) << i;
    EXPECT_EQ(back.velocities[i], frame.velocities[i]) << i;
  }
  ASSERT_EQ(back.contacts.size(), 3u);
  for (std::size_t c = 0; c < 3; ++c) {
    const Contact &a = frame.contacts[c], &b = back.contacts[c];
    EXPECT_EQ(b.position, a.position);
    EXPECT_EQ(b.normal, a.normal);
    EXPECT_EQ(b.surfaceA, a.surfaceA);
    EXPECT_EQ(b.surfaceB, a.surfaceB);
    EXPECT_EQ(b.triangleA, a.triangleA);
    EXPECT_EQ(b.triangleB, a.triangleB);
    EXPECT_EQ(b.particle, a.particle);
    EXPECT_EQ(b.kind, a.kind);
  }
}

TEST(CacheFrame, HasTheDocumentedLayout) {
  const std::string bytes = encodeCacheFrame(sampleFrame());
  ASSERT_EQ(bytes.size(), 64u + 3 * 12 + 3 * 12 + 3 * 48);
  EXPECT_EQ(std::string(bytes.data(), 8), std::string("SBCACHE\0", 8));
  EXPECT_EQ(at<std::uint32_t>(bytes, 8), 1u);   // version
  EXPECT_EQ(at<std::uint32_t>(bytes, 12), 1u);  // a frame
  EXPECT_EQ(at<std::int32_t>(bytes, 16), 37);
  EXPECT_EQ(at<std::uint32_t>(bytes, 20), 3u);  // particles
  EXPECT_EQ(at<std::uint32_t>(bytes, 24), 3u);  // contacts
  EXPECT_EQ(at<std::uint32_t>(bytes, 28), 4u);  // float32
  EXPECT_EQ(at<double>(bytes, 32), 1.5);
  EXPECT_EQ(at<std::uint64_t>(bytes, 40), bytes.size() - 64);
  EXPECT_EQ(at<std::uint32_t>(bytes, 48), referenceCrc32(std::string_view(bytes).substr(64)));
  EXPECT_EQ(at<std::uint32_t>(bytes, 52), referenceCrc32(std::string_view(bytes).substr(0, 52)));
  EXPECT_EQ(at<std::uint64_t>(bytes, 56), 0u);
  // Particle 1's position and velocity, then the second contact, a corner, field by field.
  EXPECT_EQ(at<float>(bytes, 64 + 12 + 0), 1e-3f);
  EXPECT_EQ(at<float>(bytes, 64 + 12 + 8), -7.0f);
  EXPECT_EQ(at<float>(bytes, 64 + 36 + 12 + 4), 8.0f);
  EXPECT_EQ(at<float>(bytes, 64 + 36 + 24 + 8), 1e6f);
  const std::size_t corner = 64 + 6 * 12 + 48;
  EXPECT_EQ(at<float>(bytes, corner + 8), 3.0f);                  // position z
  EXPECT_EQ(at<float>(bytes, corner + 16), 1.0f);                 // normal y
  EXPECT_EQ(at<std::uint32_t>(bytes, corner + 28), 1u);           // surface B
  EXPECT_EQ(at<std::uint32_t>(bytes, corner + 32), 0xFFFFFFFFu);  // no triangle A
  EXPECT_EQ(at<std::uint32_t>(bytes, corner + 40), 2u);           // particle
  EXPECT_EQ(at<std::uint8_t>(bytes, corner + 44), 2u);            // corner
  EXPECT_EQ(at<std::uint8_t>(bytes, corner + 48 + 44), 3u);       // plane
}

TEST(CacheFrame, EveryChangedByteIsAnErrorNamingTheFile) {
  const std::string good = encodeCacheFrame(sampleFrame());
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::string bad = good;
    bad[i] = char(bad[i] ^ 0x10);
    try {
      decodeCacheFrame(bad, "frame_0037.sbcache");
      ADD_FAILURE() << "byte " << i << " changed and the frame still loaded";
    } catch (const Error& error) {
      EXPECT_EQ(std::string(error.what()).rfind("frame_0037.sbcache: ", 0), 0u) << error.what();
    }
  }
}

TEST(CacheFrame, EveryShorterOrLongerFileIsAnError) {
  const std::string good = encodeCacheFrame(sampleFrame());
  for (std::size_t size = 0; size < good.size(); ++size)
    EXPECT_THROW(decodeCacheFrame(std::string_view(good).substr(0, size), "f"), Error) << size;
  EXPECT_THROW(decodeCacheFrame(good + '\0', "f"), Error);
}

SimulationCheckpoint sampleCheckpoint() {
  SimulationCheckpoint checkpoint;
  checkpoint.state.position = {Vec3(1, 2, 3), Vec3(-0.1f, 0.2f, 1e-7f)};
  checkpoint.state.velocity = {Vec3(0, -9.81f, 0), Vec3(4, 5, 6)};
  checkpoint.warmStart = {Vec3(1e-9f, 0, -1), Vec3(3, 2, 1)};
  checkpoint.planeHolds = {-1, 0};
  checkpoint.touchingPairs = {{3, 8}, {5, 1000000}};
  checkpoint.tangled = true;
  checkpoint.stepsTaken = 123456789012ull;
  return checkpoint;
}

TEST(CacheCheckpoint, ComesBackExactly) {
  const SimulationCheckpoint checkpoint = sampleCheckpoint();
  const DecodedCheckpoint back =
      decodeCheckpoint(encodeCheckpoint(checkpoint, 12, 0.5), "c.sbcache");
  EXPECT_EQ(back.frame, 12);
  EXPECT_EQ(back.time, 0.5);
  EXPECT_EQ(back.checkpoint.state.position, checkpoint.state.position);
  EXPECT_EQ(back.checkpoint.state.velocity, checkpoint.state.velocity);
  EXPECT_EQ(back.checkpoint.warmStart, checkpoint.warmStart);
  EXPECT_EQ(back.checkpoint.planeHolds, checkpoint.planeHolds);
  EXPECT_EQ(back.checkpoint.touchingPairs, checkpoint.touchingPairs);
  EXPECT_TRUE(back.checkpoint.tangled);
  EXPECT_EQ(back.checkpoint.stepsTaken, checkpoint.stepsTaken);

  SimulationCheckpoint explicitRun = checkpoint;  // no warm start, no holds
  explicitRun.warmStart.clear();
  explicitRun.planeHolds.clear();
  explicitRun.tangled = false;
  const DecodedCheckpoint plain = decodeCheckpoint(encodeCheckpoint(explicitRun, 2, 0), "c");
  EXPECT_TRUE(plain.checkpoint.warmStart.empty());
  EXPECT_TRUE(plain.checkpoint.planeHolds.empty());
  EXPECT_FALSE(plain.checkpoint.tangled);
}

TEST(CacheCheckpoint, RefusesAFrameAnotherPrecisionAndDamage) {
  const std::string frame = encodeCacheFrame(sampleFrame());
  EXPECT_THROW(decodeCheckpoint(frame, "f"), Error);
  const std::string good = encodeCheckpoint(sampleCheckpoint(), 12, 0.5);
  EXPECT_THROW(decodeCacheFrame(good, "c"), Error);
  // The other build's checkpoint: its scalar size, with a header checksum that matches.
  std::string other = good;
  const std::uint32_t otherBytes = sizeof(Scalar) == 4 ? 8 : 4;
  std::memcpy(other.data() + 28, &otherBytes, 4);
  const std::uint32_t crc = referenceCrc32(std::string_view(other).substr(0, 52));
  std::memcpy(other.data() + 52, &crc, 4);
  try {
    decodeCheckpoint(other, "c.sbcache");
    ADD_FAILURE() << "a checkpoint of the other precision loaded";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("-bit"), std::string::npos) << error.what();
  }
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::string bad = good;
    bad[i] = char(bad[i] ^ 0x01);
    EXPECT_THROW(decodeCheckpoint(bad, "c"), Error) << "byte " << i;
  }
}

}  // namespace
}  // namespace softbake
