// Files that make assimp 5.2 itself crash (found by fuzzing, fuzz/README.md): assimp reads in a
// child process, so each ends in an error naming the file, and this process goes on. Where
// softbake knows the bug, it steps around it and says what the file lost instead.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdio.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "importers/assimp_snapshot.hpp"
#include "importers/mesh_import.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using test::importError;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// assimp 5.2.5's MTL reader segfaults on a texture statement at the very end of the file.
TEST(AssimpCrash, AnObjWhoseMaterialLibraryCrashesAssimpIsAnErrorNamingTheFile) {
  test::ScratchDir dir;
  dir.write("crash.mtl", "map_Kd x");
  const auto obj = dir.write("box.obj",
                             "mtllib crash.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                             "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  EXPECT_EQ(importError(obj), obj.string() +
                                  ": assimp crashed reading the file (Segmentation fault): the "
                                  "file is corrupt, or trips a bug in assimp");
  // The same OBJ with a sound library imports: the crash was the library's.
  dir.write("crash.mtl", "newmtl red\nKd 1 0 0\n");
  EXPECT_EQ(importMeshFile(obj).meshes.at(0).triangles.size(), 4u);
}

// A tetrahedron as binary PLY whose last two faces have no corners: assimp 5.2.5 passes them
// through validation and then aborts in its Triangulate step.
std::string plyWithEmptyFaces() {
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nelement face 6\n"
      "property list uchar uint vertex_indices\nend_header\n";
  const float positions[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  ply.append(reinterpret_cast<const char*>(positions), sizeof positions);
  const std::uint32_t faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& face : faces) {
    ply += char(3);
    ply.append(reinterpret_cast<const char*>(face), sizeof face);
  }
  ply += std::string(2, '\0');  // two faces of 0 corners
  return ply;
}

TEST(AssimpCrash, FacesWithNoCornersAreALossNotACrash) {
  test::ScratchDir dir;
  const auto file = dir.write("empty_faces.ply", plyWithEmptyFaces());
  EXPECT_THAT(importError(file),
              StartsWith(file.string() + ": the import lost geometry: 2 faces with no corners. "
                                         "Refused"));
  const ImportedMeshes accepted = importMeshFile(file, {.acceptLossy = true});
  ASSERT_EQ(accepted.meshes.size(), 1u);
  EXPECT_EQ(accepted.meshes[0].triangles.size(), 4u);
  EXPECT_THAT(accepted.warnings.at(0), HasSubstr("2 faces with no corners; imported what is left"));
}

// The child's answer, through a file standing in for the pipe.
class SnapshotBytes : public ::testing::Test {
 protected:
  SnapshotBytes() : file_(std::tmpfile()) {}
  ~SnapshotBytes() override { std::fclose(file_); }
  int fd() const { return fileno(file_); }
  void rewind() const { ::lseek(fd(), 0, SEEK_SET); }
  FILE* file_;
};

TEST_F(SnapshotBytes, ComeBackAsTheSnapshotThatWasSent) {
  AssimpSnapshot sent;
  sent.loaderVertices = 7;
  sent.loaderFaces = 5;
  sent.loaderMeshVertices = {4, 3};
  sent.unusedVertices = 1;
  sent.emptyFaces = 2;
  SnapshotMesh mesh;
  mesh.name = "cube";
  mesh.positions = {Vec3f(1, 2, 3), Vec3f(-4, 5.5f, 6)};
  mesh.uvs = {Vec2f(0.25f, 1), Vec2f(0, 0)};
  mesh.triangles = {{0, 1, 1}};
  mesh.points = 3;
  mesh.lines = 4;
  sent.meshes = {mesh};
  SnapshotNode root;
  root.name = "root";
  root.transform(0, 3) = 2.5;
  root.meshes = {0};
  root.children = {1};
  sent.nodes = {root, SnapshotNode{}};
  sent.messages = {{AssimpMessage::Severity::Error, "bad face", 3}};
  sent.unkeptMessages = 9;
  ASSERT_TRUE(writeAssimpSnapshot(fd(), sent));
  rewind();
  const AssimpSnapshot got = readAssimpSnapshot(fd());
  EXPECT_EQ(got.loaderVertices, 7u);
  EXPECT_EQ(got.loaderFaces, 5u);
  EXPECT_EQ(got.loaderMeshVertices, sent.loaderMeshVertices);
  EXPECT_EQ(got.unusedVertices, 1u);
  EXPECT_EQ(got.emptyFaces, 2u);
  ASSERT_EQ(got.meshes.size(), 1u);
  EXPECT_EQ(got.meshes[0].name, "cube");
  EXPECT_EQ(got.meshes[0].positions, mesh.positions);
  EXPECT_TRUE(got.meshes[0].normals.empty());
  EXPECT_EQ(got.meshes[0].uvs, mesh.uvs);
  EXPECT_EQ(got.meshes[0].triangles, mesh.triangles);
  EXPECT_EQ(got.meshes[0].points, 3u);
  EXPECT_EQ(got.meshes[0].lines, 4u);
  ASSERT_EQ(got.nodes.size(), 2u);
  EXPECT_EQ(got.nodes[0].transform, root.transform);
  EXPECT_EQ(got.nodes[0].children, root.children);
  ASSERT_EQ(got.messages.size(), 1u);
  EXPECT_EQ(got.messages[0].severity, AssimpMessage::Severity::Error);
  EXPECT_EQ(got.messages[0].text, "bad face");
  EXPECT_EQ(got.messages[0].repeats, 3u);
  EXPECT_EQ(got.unkeptMessages, 9u);
}

// A child that dies mid-answer leaves it cut short: every cut is an error, never a snapshot.
TEST_F(SnapshotBytes, AnAnswerCutShortIsAnError) {
  AssimpSnapshot sent;
  sent.meshes.resize(1);
  sent.meshes[0].positions.assign(1000, Vec3f(1, 2, 3));
  ASSERT_TRUE(writeAssimpSnapshot(fd(), sent));
  const off_t size = ::lseek(fd(), 0, SEEK_END);
  for (off_t cut : {size - 1, size / 2, off_t(100), off_t(5), off_t(0)}) {
    ASSERT_EQ(::ftruncate(fd(), cut), 0);
    rewind();
    EXPECT_THROW(readAssimpSnapshot(fd()), std::runtime_error) << "cut at " << cut;
  }
}

}  // namespace
}  // namespace softbake
