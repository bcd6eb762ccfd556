// No NaN or infinity reaches an output file: every writer refuses a frame holding one, with an
// error naming the file and the value, and leaves no file (not even a temporary one) behind.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "exporters/contact_writer.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "exporters/vdb_sequence_writer.hpp"
#include "output/manifest.hpp"
#include "test_world.hpp"

namespace softbake {
namespace {

using test::listDirectory;
using test::makeBallsTopology;
using test::ScratchDirectory;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr Scalar kNaN = std::numeric_limits<Scalar>::quiet_NaN();
constexpr Scalar kInfinity = std::numeric_limits<Scalar>::infinity();

Frame restFrame(const SceneTopology& world, int number) {
  Frame frame;
  frame.number = number;
  frame.time = (number - 1) / 24.0;
  frame.positions = world.restPosition;
  frame.velocities.assign(world.particleCount(), Vec3(0, -1, 0));
  return frame;
}

Contact contactAt(const Vec3& position, const Vec3& normal) {
  Contact contact;
  contact.kind = ContactKind::ParticleTriangle;
  contact.position = position;
  contact.normal = normal;
  contact.surfaceA = 1;
  contact.surfaceB = 0;
  return contact;
}

// The message `write` fails with; a test failure when it does not fail.
template <class Write>
std::string errorOf(Write&& write) {
  try {
    write();
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "no error";
  return {};
}

TEST(NonFiniteOutput, ObjFrameWithANaNPositionIsRefusedNamingFileBodyAndParticle) {
  const auto world = makeBallsTopology({1.0f, 0.5f});
  ScratchDirectory out;
  ObjSequenceWriter writer(world, out.path(), "balls");
  Frame frame = restFrame(*world, 7);
  Vec3& bad = frame.positions[world->bodies[1].firstParticle + 5];
  bad = Vec3(1.5f, kNaN, -2);
  EXPECT_EQ(errorOf([&] { writer.write(frame); }),
            writer.framePath(7).string() +
                ": not written: frame 7: body 'ball1': the position of particle 5 is not finite "
                "(1.5, nan, -2)");
  EXPECT_EQ(listDirectory(out.path() / "obj"), std::vector<std::string>{"balls.mtl"});
}

TEST(NonFiniteOutput, ObjFrameWithAnInfiniteTimeIsRefused) {
  const auto world = makeBallsTopology({1.0f});
  ScratchDirectory out;
  ObjSequenceWriter writer(world, out.path(), "balls");
  Frame frame = restFrame(*world, 3);
  frame.time = kInfinity;
  EXPECT_EQ(errorOf([&] { writer.write(frame); }),
            writer.framePath(3).string() + ": not written: frame 3: the time is not finite (inf)");
  EXPECT_EQ(listDirectory(out.path() / "obj"), std::vector<std::string>{"balls.mtl"});
}

// Every frame repeats the UVs: a NaN among them is refused before the first file.
TEST(NonFiniteOutput, ObjSequenceWithANaNUvIsRefusedBeforeAnyFile) {
  SceneSetup setup;
  BodySetup quad;
  quad.name = "flag";
  quad.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.mesh.uvs = {{0, 0}, {1, 0}, {1, std::numeric_limits<float>::quiet_NaN()}, {0, 1}};
  quad.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  setup.bodies.push_back(quad);
  const auto world = std::make_shared<const SceneTopology>(buildSceneTopology(setup));
  ScratchDirectory out;
  EXPECT_THAT(errorOf([&] { ObjSequenceWriter(world, out.path(), "flag"); }),
              AllOf(StartsWith((out.path() / "obj" / "flag_####.obj").string() +
                               ": not written: body 'flag': the UV of render vertex "),
                    HasSubstr(" is not finite (1, nan)")));
  EXPECT_TRUE(listDirectory(out.path()).empty());
}

TEST(NonFiniteOutput, ContactFrameWithANaNContactIsRefusedNamingFileAndBodies) {
  const auto world = makeBallsTopology({0.5f, 0.5f});
  ScratchDirectory out;
  ContactWriter writer(*world, out.path(), "balls");
  Frame frame = restFrame(*world, 4);
  frame.contacts = {contactAt(Vec3(1, 2, 3), Vec3(0, 1, 0)),
                    contactAt(Vec3(1, 2, 3), Vec3(0, kNaN, 0))};
  EXPECT_EQ(errorOf([&] { writer.write(frame); }),
            writer.framePath(4).string() +
                ": not written: frame 4: the normal of contact 1 (ball1 on ball0) is not finite "
                "(0, nan, 0)");
  frame.contacts = {contactAt(Vec3(kInfinity, 2, 3), Vec3(0, 1, 0))};
  EXPECT_THAT(errorOf([&] { writer.write(frame); }),
              HasSubstr(": not written: frame 4: the position of contact 0 (ball1 on ball0) is "
                        "not finite (inf, 2, 3)"));
  frame.contacts.clear();
  frame.time = kNaN;
  EXPECT_THAT(errorOf([&] { writer.write(frame); }),
              HasSubstr(": not written: frame 4: the time is not finite (nan)"));
  EXPECT_TRUE(listDirectory(out.path() / "contacts").empty());
}

class NonFiniteVdb : public ::testing::Test {
 protected:
  NonFiniteVdb() : world_(makeBallsTopology({1.0f})) {
    VdbOptions options;
    options.voxelSize = 0.2;
    writer_ = std::make_unique<VdbSequenceWriter>(*world_, out_.path(), "ball", options);
  }
  // The error writing `frame` gives; no file may be left in OUT/vdb.
  std::string refused(const Frame& frame) {
    const std::string message = errorOf([&] { writer_->write(frame); });
    EXPECT_TRUE(listDirectory(out_.path() / "vdb").empty());
    return message;
  }
  std::shared_ptr<const SceneTopology> world_;
  ScratchDirectory out_;
  std::unique_ptr<VdbSequenceWriter> writer_;
};

TEST_F(NonFiniteVdb, APositionIsRefusedNamingTheFile) {
  Frame frame = restFrame(*world_, 2);
  frame.positions[9].z() = -kInfinity;
  EXPECT_THAT(refused(frame),
              AllOf(StartsWith(writer_->framePath(2).string() +
                               ": not written: frame 2: body 'ball0': the position of particle 9 "
                               "is not finite ("),
                    HasSubstr(", -inf)")));
}

TEST_F(NonFiniteVdb, AVelocityIsRefusedNamingTheFile) {
  Frame frame = restFrame(*world_, 2);
  frame.velocities[11] = Vec3(kNaN, 0, 0);
  EXPECT_EQ(refused(frame), writer_->framePath(2).string() +
                                ": not written: frame 2: body 'ball0': the velocity of particle "
                                "11 is not finite (nan, 0, 0)");
}

TEST_F(NonFiniteVdb, AContactIsRefusedNamingTheFile) {
  Frame frame = restFrame(*world_, 2);
  frame.contacts = {contactAt(Vec3(0, 1, 0), Vec3(0, 1, 0))};
  frame.contacts[0].surfaceA = 0;
  frame.contacts[0].position.x() = kNaN;
  EXPECT_EQ(refused(frame), writer_->framePath(2).string() +
                                ": not written: frame 2: the position of contact 0 is not finite "
                                "(nan, 1, 0)");
}

TEST_F(NonFiniteVdb, ATimeIsRefusedNamingTheFile) {
  Frame frame = restFrame(*world_, 2);
  frame.time = kNaN;
  EXPECT_EQ(refused(frame), writer_->framePath(2).string() +
                                ": not written: frame 2: the time is not finite (nan)");
}

TEST(NonFiniteOutput, ManifestWithANaNFpsIsRefused) {
  ScratchDirectory out;
  Manifest manifest = describeScene(*makeBallsTopology({1.0f}), "balls", 3);
  manifest.fps = kNaN;
  EXPECT_EQ(errorOf([&] { writeManifest(out.path(), manifest); }),
            (out.path() / "manifest.json").string() +
                ": not written: the scene's fps is not finite (nan)");
  EXPECT_TRUE(listDirectory(out.path()).empty());
}

}  // namespace
}  // namespace softbake
