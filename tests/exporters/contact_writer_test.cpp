// ContactWriter: one JSON file per frame, bodies by name, indices local to each body, the same
// sequence naming as the OBJ files.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "exporters/contact_writer.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "test_world.hpp"

namespace softbake {
namespace {

TEST(ContactWriter, WritesEachFramesContactsWithNamesAndLocalIndices) {
  test::ScratchDirectory out;
  const auto world = test::makeBallsTopology({0.5f, 0.5f});
  const Body& second = world->bodies[1];
  ContactWriter writer(*world, out.path(), "balls", 4);

  Frame frame;
  frame.number = 7;
  frame.time = 0.25;
  frame.positions = world->restPosition;
  Contact particle;
  particle.kind = ContactKind::ParticleTriangle;
  particle.position = Vec3(1, 2, 3);
  particle.normal = Vec3(0, 1, 0);
  particle.surfaceA = 1;
  particle.surfaceB = 0;
  particle.particle = second.firstParticle + 5;
  particle.triangleB = 12;
  Contact edge;
  edge.kind = ContactKind::EdgeTriangle;
  edge.surfaceA = 0;
  edge.surfaceB = 1;
  edge.triangleA = 3;
  edge.triangleB = second.firstTriangle + 9;
  frame.contacts = {particle, edge};
  writer.write(frame);

  const std::filesystem::path path = out.path() / "contacts" / "balls_0007.json";
  ASSERT_EQ(writer.framePath(7), path);
  const nlohmann::json json = nlohmann::json::parse(test::readFile(path));
  EXPECT_EQ(json.at("frame"), 7);
  EXPECT_DOUBLE_EQ(json.at("time").get<double>(), 0.25);
  ASSERT_EQ(json.at("contacts").size(), 2u);
  const nlohmann::json& first = json["contacts"][0];
  EXPECT_EQ(first.at("kind"), "particle-triangle");
  EXPECT_EQ(first.at("bodies"), nlohmann::json::array({"ball1", "ball0"}));
  EXPECT_EQ(first.at("particle"), 5);
  EXPECT_TRUE(first.at("triangles")[0].is_null());
  EXPECT_EQ(first.at("triangles")[1], 12);
  EXPECT_EQ(first.at("position"), nlohmann::json::array({1.0, 2.0, 3.0}));
  const nlohmann::json& second_ = json["contacts"][1];
  EXPECT_EQ(second_.at("kind"), "edge-triangle");
  EXPECT_TRUE(second_.at("particle").is_null());
  EXPECT_EQ(second_.at("triangles"), nlohmann::json::array({3, 9}));
  EXPECT_GT(writer.bytesWritten(), 0u);
}

TEST(ContactWriter, APlaneContactNamesThePlaneAndHasNoTriangles) {
  test::ScratchDirectory out;
  SceneTopology world = *test::makeBallsTopology({0.5f, 0.5f});
  world.planes.push_back(PlaneCollider{.name = "floor"});
  world.planes.push_back(PlaneCollider{.name = "wall", .normal = Vec3(1, 0, 0)});
  ContactWriter writer(world, out.path(), "balls", 4);

  Frame frame;
  frame.number = 2;
  frame.positions = world.restPosition;
  Contact onWall;
  onWall.kind = ContactKind::Plane;
  onWall.position = Vec3(0, 1, 0);
  onWall.normal = Vec3(1, 0, 0);
  onWall.surfaceA = 1;
  onWall.surfaceB = 1;
  onWall.particle = world.bodies[1].firstParticle + 4;
  frame.contacts = {onWall};
  writer.write(frame);

  const nlohmann::json json = nlohmann::json::parse(test::readFile(writer.framePath(2)));
  ASSERT_EQ(json.at("contacts").size(), 1u);
  const nlohmann::json& contact = json["contacts"][0];
  EXPECT_EQ(contact.at("kind"), "plane");
  EXPECT_EQ(contact.at("bodies"), nlohmann::json::array({"ball1", "wall"}));
  EXPECT_EQ(contact.at("triangles"), nlohmann::json::array({nullptr, nullptr}));
  EXPECT_EQ(contact.at("particle"), 4);
  EXPECT_EQ(contact.at("normal"), nlohmann::json::array({1.0, 0.0, 0.0}));
}

TEST(ContactWriter, SequenceIsNamedLikeTheObjSequence) {
  test::ScratchDirectory out;
  const auto world = test::makeBallsTopology({0.5f});
  const ContactWriter contacts(*world, out.path(), "balls", 5);
  const ObjSequenceWriter obj(world, out.path(), "balls", 5);
  EXPECT_EQ(contacts.sequence().pattern, "contacts/balls_#####.json");
  EXPECT_EQ(contacts.framePath(42).stem(), obj.framePath(42).stem());
}

}  // namespace
}  // namespace softbake
