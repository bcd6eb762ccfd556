// Every good test mesh through importMeshFile, checked after core's weld against the counts of
// how each file was made (tests/data/meshes/README.md).

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>
#include <assimp/Importer.hpp>

#include <Eigen/Geometry>
#include <set>

#include "core/mesh/mesh_topology.hpp"
#include "core/mesh/weld.hpp"
#include "generated_meshes.hpp"
#include "importers/mesh_import.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

struct SharedMesh {
  const char* file;
  std::size_t particles;  ///< distinct positions that a triangle uses
  std::size_t triangles;
  bool closed;  ///< watertight after the weld
  /// Writes a stand-in for the file, which then is not one of tests/data; null for the others.
  std::string (*generate)() = nullptr;
};

using test::ScanPly;
using test::TexturedObj;

// The counts of the copied files are the shared snapshot README's "uniq pos" and face counts.
const SharedMesh kSharedMeshes[] = {
    {"textured.obj", TexturedObj::kPositions, TexturedObj::kTriangles, true, &TexturedObj::text},
    {"ico4.obj", 642, 1280, true},
    {"scan.ply", ScanPly::kFileVertices - ScanPly::kUnreferencedVertices, ScanPly::kTriangles,
     false, &ScanPly::text},
    {"fuze.ply", 502, 1000, true},
    {"torus.STL", 4350, 8700, true},
    {"sphereWithHole.stl", 146, 285, false},
    {"AnimatedMorphSphere.gltf", 482, 960, true},
    {"duck.dae", 2108, 4212, true},
    {"fels.3ds", 386, 768, true},
    {"ballA.off", 1900, 3796, true},
    {"cubes_with_mirroring_and_pivot.fbx", 220, 420, true},
};

class SharedMeshTest : public ::testing::TestWithParam<SharedMesh> {};

TEST_P(SharedMeshTest, WeldsToTheUniquePositionsOfTheFile) {
  const SharedMesh& expected = GetParam();
  test::ScratchDir dir;
  const std::filesystem::path file = expected.generate
                                         ? dir.write(expected.file, expected.generate())
                                         : test::testMeshes() / expected.file;
  const ImportedMeshes imported = importMeshFile(file, {.mergeMeshes = true});
  ASSERT_EQ(imported.meshes.size(), 1u);
  const TriangleMesh& mesh = imported.meshes[0];
  EXPECT_EQ(mesh.name, std::filesystem::path(expected.file).stem().string());
  EXPECT_EQ(mesh.triangles.size(), expected.triangles);
  for (const Vec3f& p : mesh.positions) ASSERT_TRUE(p.allFinite());
  if (!mesh.normals.empty()) {
    EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
  }
  if (!mesh.uvs.empty()) {
    EXPECT_EQ(mesh.uvs.size(), mesh.positions.size());
  }

  const WeldedMesh welded = weldByPosition(mesh.positions, mesh.triangles);
  EXPECT_EQ(welded.positions.size(), expected.particles);
  EXPECT_EQ(buildTopology(welded.triangles).closed(), expected.closed);
  // Every closed file comes out wound outward, mirrored FBX instances included.
  if (expected.closed) {
    EXPECT_GT(signedVolume(welded.positions, welded.triangles), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, SharedMeshTest, ::testing::ValuesIn(kSharedMeshes),
                         [](const auto& param) {
                           std::string name = param.param.file;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

TEST(MeshImport, ScanParticlesAreItsReferencedPositions) {
  test::ScratchDir dir;
  const ImportedMeshes imported = importMeshFile(dir.write("scan.ply", ScanPly::text()));
  ASSERT_EQ(imported.meshes.size(), 1u);
  const TriangleMesh& mesh = imported.meshes[0];
  // The importer keeps every file vertex; the weld sets the unused ones aside.
  EXPECT_EQ(mesh.positions.size(), ScanPly::kFileVertices);
  const WeldedMesh welded = weldByPosition(mesh.positions, mesh.triangles);
  EXPECT_EQ(welded.unreferencedVertices, ScanPly::kUnreferencedVertices);
  EXPECT_EQ(welded.positions.size() + welded.unreferencedVertices, ScanPly::kFileVertices);
}

TEST(MeshImport, KeepsUvsAndNormalsOfTheFile) {
  test::ScratchDir dir;
  const TriangleMesh textured =
      importMeshFile(dir.write("textured.obj", TexturedObj::text())).meshes.at(0);
  EXPECT_EQ(textured.uvs.size(), textured.positions.size());
  EXPECT_TRUE(textured.normals.empty());  // the file has none and nothing generates them
  // The seam and the poles split positions by UV; the weld joins them again.
  EXPECT_GT(textured.positions.size(), TexturedObj::kPositions);
  Eigen::AlignedBox2f uvBounds;
  for (const Vec2f& uv : textured.uvs) uvBounds.extend(uv);
  EXPECT_TRUE(uvBounds.min().isApprox(Vec2f(0, 0))) << uvBounds.min().transpose();
  EXPECT_TRUE(uvBounds.max().isApprox(Vec2f(1, 1))) << uvBounds.max().transpose();

  const TriangleMesh ico = importMeshFile(test::testMeshes() / "ico4.obj").meshes.at(0);
  EXPECT_TRUE(ico.uvs.empty());
  ASSERT_EQ(ico.normals.size(), ico.positions.size());
  // Flat normals: each one is its triangle's outward face normal.
  for (const Triangle& t : ico.triangles) {
    const Vec3f face = (ico.positions[t[1]] - ico.positions[t[0]])
                           .cross(ico.positions[t[2]] - ico.positions[t[0]])
                           .normalized();
    for (Index v : t) EXPECT_GT(ico.normals[v].dot(face), 0.99f);
  }
}

// World transforms of every mesh instance, read with assimp directly.
std::vector<double> instanceDeterminants(const std::filesystem::path& file) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(file.string(), aiProcess_Triangulate);
  std::vector<double> determinants;
  std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack = {
      {scene->mRootNode, scene->mRootNode->mTransformation}};
  while (!stack.empty()) {
    auto [node, world] = stack.back();
    stack.pop_back();
    for (unsigned i = 0; i < node->mNumMeshes; ++i) determinants.push_back(world.Determinant());
    for (unsigned i = 0; i < node->mNumChildren; ++i)
      stack.emplace_back(node->mChildren[i], world * node->mChildren[i]->mTransformation);
  }
  return determinants;
}

TEST(MeshImport, MirroredFbxInstancesComeOutWoundOutward) {
  const std::filesystem::path file = test::testMeshes() / "cubes_with_mirroring_and_pivot.fbx";
  const std::vector<double> determinants = instanceDeterminants(file);
  ASSERT_EQ(determinants.size(), 4u);
  EXPECT_EQ(std::count_if(determinants.begin(), determinants.end(), [](double d) { return d < 0; }),
            2);

  const ImportedMeshes imported = importMeshFile(file);
  ASSERT_EQ(imported.meshes.size(), 4u);
  std::set<std::string> names;
  double total = 0;
  for (const TriangleMesh& mesh : imported.meshes) {
    names.insert(mesh.name);
    const WeldedMesh welded = weldByPosition(mesh.positions, mesh.triangles);
    EXPECT_TRUE(buildTopology(welded.triangles).closed()) << mesh.name;
    const double volume = signedVolume(welded.positions, welded.triangles);
    EXPECT_GT(volume, 0) << mesh.name;
    total += volume;
    // Normals went through the inverse-transpose and still agree with the flipped winding.
    ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
    for (const Triangle& t : mesh.triangles) {
      const Vec3f face = (mesh.positions[t[1]] - mesh.positions[t[0]])
                             .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
      for (Index v : t) EXPECT_GT(mesh.normals[v].dot(face), 0) << mesh.name;
      for (Index v : t) EXPECT_NEAR(mesh.normals[v].norm(), 1, 1e-5);
    }
  }
  EXPECT_EQ(names, (std::set<std::string>{"Cube1", "Cube1_2", "Cube2", "Cube3"}));

  // The hollow cube (outer +2, inner cavity -1 in its own units) keeps its cavity inward.
  const TriangleMesh merged = importMeshFile(file, {.mergeMeshes = true}).meshes.at(0);
  const WeldedMesh welded = weldByPosition(merged.positions, merged.triangles);
  EXPECT_NEAR(signedVolume(welded.positions, welded.triangles), total,
              1e-6 * std::abs(total) + 1e-12);
}

Eigen::AlignedBox3f boundsOf(const TriangleMesh& mesh) {
  Eigen::AlignedBox3f bounds;
  for (const Vec3f& p : mesh.positions) bounds.extend(p);
  return bounds;
}

// Largest side of the file's meshes in their own coordinates, node transforms ignored.
float localLargestSide(const std::filesystem::path& file) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(file.string(), aiProcess_Triangulate);
  Eigen::AlignedBox3f bounds;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m)
    for (unsigned v = 0; v < scene->mMeshes[m]->mNumVertices; ++v) {
      const aiVector3D& p = scene->mMeshes[m]->mVertices[v];
      bounds.extend(Vec3f(p.x, p.y, p.z));
    }
  return bounds.sizes().maxCoeff();
}

TEST(MeshImport, AppliesTheGltfNodeScaleOf100) {
  const std::filesystem::path file = test::testMeshes() / "AnimatedMorphSphere.gltf";
  const float local = localLargestSide(file);
  EXPECT_NEAR(local, 0.02f, 0.002f);  // "about 0.01 units across" in the README's words
  const float world = boundsOf(importMeshFile(file).meshes.at(0)).sizes().maxCoeff();
  EXPECT_NEAR(world / local, 100, 0.01);
  EXPECT_NEAR(world, 2, 0.2);  // a sphere of radius about 1
}

TEST(MeshImport, AppliesTheColladaDuckNodeScaleOfOneHundredth) {
  const std::filesystem::path file = test::testMeshes() / "duck.dae";
  const TriangleMesh duck = importMeshFile(file).meshes.at(0);
  EXPECT_EQ(duck.name, "LOD3sp");  // the node, not the camera or the light
  const float world = boundsOf(duck).sizes().maxCoeff();
  EXPECT_NEAR(world / localLargestSide(file), 0.01, 1e-5);
  EXPECT_GT(world, 1);
  EXPECT_LT(world, 2);
}

TEST(MeshImport, NamesMeshesAfterNodesThenMeshesThenTheFile) {
  test::ScratchDir dir;
  EXPECT_EQ(importMeshFile(dir.write("textured.obj", TexturedObj::text())).meshes.at(0).name,
            "defaultobject");
  // "<OFFRoot>" is made up by assimp and the OFF mesh has no name: the file stem it is.
  EXPECT_EQ(importMeshFile(test::testMeshes() / "ballA.off").meshes.at(0).name, "ballA");
  EXPECT_EQ(importMeshFile(test::testMeshes() / "fels.3ds").meshes.at(0).name, "3DSMesh_0");
}

TEST(MeshImport, DropsPointsAndLinesWithANote) {
  test::ScratchDir dir;
  const auto file = dir.write("mixed.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "f 1 2 3\nl 1 4\nl 2 4\np 4\n");
  const ImportedMeshes imported = importMeshFile(file);
  ASSERT_EQ(imported.meshes.size(), 1u);
  EXPECT_EQ(imported.meshes[0].triangles.size(), 1u);
  ASSERT_EQ(imported.notes.size(), 1u);
  EXPECT_EQ(imported.notes[0],
            file.string() + ": ignored 1 points and 2 lines (only triangles are simulated)");
}

TEST(MeshImport, MergingDropsUvsThatOnlySomeMeshesHaveWithANote) {
  test::ScratchDir dir;
  const auto file = dir.write("parts.obj",
                              "o textured\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                              "f 1/1 2/2 3/3\n"
                              "o plain\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n");
  const ImportedMeshes separate = importMeshFile(file);
  ASSERT_EQ(separate.meshes.size(), 2u);
  EXPECT_EQ(separate.meshes[0].uvs.size(), 3u);
  EXPECT_TRUE(separate.meshes[1].uvs.empty());
  EXPECT_TRUE(separate.notes.empty());

  const ImportedMeshes merged = importMeshFile(file, {.mergeMeshes = true});
  ASSERT_EQ(merged.meshes.size(), 1u);
  const TriangleMesh& mesh = merged.meshes[0];
  EXPECT_EQ(mesh.name, "parts");
  EXPECT_EQ(mesh.positions.size(), 6u);
  EXPECT_TRUE(mesh.uvs.empty());
  // The second triangle's indices were offset past the first mesh's vertices.
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[1], (Triangle{3, 4, 5}));
  ASSERT_EQ(merged.notes.size(), 1u);
  EXPECT_EQ(merged.notes[0],
            file.string() + ": not every mesh has UVs, so the merged mesh has none");
}

}  // namespace
}  // namespace softbake
