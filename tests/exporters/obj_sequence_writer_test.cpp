#include "exporters/obj_sequence_writer.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/version.hpp"
#include "test_world.hpp"
#include "tests/support/obj_text.hpp"

namespace softbake {
namespace {

using test::listDirectory;
using test::makeBallsTopology;
using test::ParsedObj;
using test::parseObj;
using test::readFile;
using test::ScratchDirectory;

/// The world's rest positions, stretched and rippled so every coordinate is an unremarkable float.
Frame deformedFrame(const std::shared_ptr<const SceneTopology>& world, int number) {
  Frame frame;
  frame.number = number;
  frame.time = (number - 1) / 24.0;
  frame.positions = world->restPosition;
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    Vec3& p = frame.positions[i];
    p.x() *= Scalar(1.1);
    p.y() += Scalar(0.013 * std::sin(double(i) * 0.7 + number));
    p.z() -= Scalar(0.002 * double(number));
  }
  return frame;
}

/// The normals the OBJ must carry, computed here rather than by core's computeSmoothNormals: per
/// particle, the sum of its triangles' cross products (each twice the triangle's area times its
/// unit normal) in double, normalised. In the body's particle order.
std::vector<Vec3d> referenceNormals(const std::shared_ptr<const SceneTopology>& world,
                                    const Frame& frame, const Body& body) {
  std::vector<Vec3d> sums(body.particleCount, Vec3d::Zero());
  for (Index t = body.firstTriangle; t < body.firstTriangle + body.triangleCount; ++t) {
    const Triangle& tri = world->triangles[t];
    const Vec3d a = frame.positions[tri[0]].cast<double>(),
                b = frame.positions[tri[1]].cast<double>(),
                c = frame.positions[tri[2]].cast<double>();
    for (Index v : tri) sums[v - body.firstParticle] += (b - a).cross(c - a);
  }
  for (Vec3d& n : sums) n.normalize();
  return sums;
}

/// Float normals against the double reference: the writer's are summed in float. Measured 1.1e-7,
/// two float roundings.
constexpr double kNormalTolerance = 3e-7;

TEST(ObjSequenceWriter, ReadsBackThroughAssimpWithTheWrittenUvsAndNormals) {
  const auto world = makeBallsTopology({1.0f, 0.5f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  const Frame frame = deformedFrame(world, 2);
  writer.write(frame);

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(writer.framePath(2).string(), aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, world->bodies.size());
  for (std::size_t b = 0; b < world->bodies.size(); ++b) {
    const Body& body = world->bodies[b];
    const aiMesh& mesh = *scene->mMeshes[b];
    ASSERT_EQ(mesh.mNumFaces, body.triangleCount) << body.name;
    ASSERT_TRUE(mesh.HasNormals());
    ASSERT_TRUE(mesh.HasTextureCoords(0));
    aiString material;
    scene->mMaterials[mesh.mMaterialIndex]->Get(AI_MATKEY_NAME, material);
    EXPECT_EQ(std::string(material.C_Str()), body.name);

    const std::vector<Vec3d> normals = referenceNormals(world, frame, body);
    for (Index f = 0; f < body.triangleCount; ++f) {
      const aiFace& face = mesh.mFaces[f];
      ASSERT_EQ(face.mNumIndices, 3u);
      for (int k = 0; k < 3; ++k) {
        const unsigned vertex = face.mIndices[k];
        const Index particle = world->triangles[body.firstTriangle + f][k];
        const Vec3& p = frame.positions[particle];
        // assimp's own float parser may round the last bit differently; exactness is checked
        // with from_chars below.
        EXPECT_NEAR(mesh.mVertices[vertex].x, p.x(), 1e-6f);
        EXPECT_NEAR(mesh.mVertices[vertex].y, p.y(), 1e-6f);
        EXPECT_NEAR(mesh.mVertices[vertex].z, p.z(), 1e-6f);
        const aiVector3D& n = mesh.mNormals[vertex];
        EXPECT_NEAR(n.Length(), 1.0f, 1e-5f);
        const Vec3d& expected = normals[particle - body.firstParticle];
        EXPECT_NEAR(n.x, expected.x(), kNormalTolerance);
        EXPECT_NEAR(n.y, expected.y(), kNormalTolerance);
        EXPECT_NEAR(n.z, expected.z(), kNormalTolerance);
        const Vec2f& uv = body.render.uvs[body.render.renderTriangles[f][k]];
        EXPECT_NEAR(mesh.mTextureCoords[0][vertex].x, uv.x(), 1e-6f);
        EXPECT_NEAR(mesh.mTextureCoords[0][vertex].y, uv.y(), 1e-6f);
      }
    }
  }
}

TEST(ObjSequenceWriter, WritesExactShortestFormsAndGlobalIndices) {
  const auto world = makeBallsTopology({1.0f, 0.5f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  const Frame frame = deformedFrame(world, 3);
  writer.write(frame);
  const ParsedObj obj = parseObj(readFile(writer.framePath(3)));

  EXPECT_EQ(obj.mtllib, "balls.mtl");
  EXPECT_EQ(obj.objects, (std::vector<std::string>{"ball0", "ball1"}));
  EXPECT_EQ(obj.materials, obj.objects);
  // Bit-exact: the shortest form reads back to the very same float.
  ASSERT_EQ(obj.v.size(), frame.positions.size());
  for (std::size_t i = 0; i < obj.v.size(); ++i) EXPECT_EQ(obj.v[i], frame.positions[i]) << i;

  // Each distinct UV once per body, in order of first use by its faces.
  std::vector<Vec2f> uvs;
  std::vector<Vec3d> normals;
  for (const Body& body : world->bodies) {
    const std::size_t first = uvs.size();
    for (const Triangle& triangle : body.render.renderTriangles)
      for (Index v : triangle)
        if (std::find(uvs.begin() + long(first), uvs.end(), body.render.uvs[v]) == uvs.end())
          uvs.push_back(body.render.uvs[v]);
    const std::vector<Vec3d> bodyNormals = referenceNormals(world, frame, body);
    normals.insert(normals.end(), bodyNormals.begin(), bodyNormals.end());
  }
  EXPECT_EQ(obj.vt, uvs);
  ASSERT_EQ(obj.vn.size(), normals.size());
  double worst = 0;
  for (std::size_t i = 0; i < normals.size(); ++i)
    worst = std::max(worst, (obj.vn[i].cast<double>() - normals[i]).cwiseAbs().maxCoeff());
  char measured[32];
  std::snprintf(measured, sizeof measured, "%.3g", worst);
  RecordProperty("worst_normal_error", measured);
  EXPECT_LE(worst, kNormalTolerance);

  ASSERT_EQ(obj.faces.size(), world->triangles.size());
  long uvBegin = 0;
  for (std::size_t b = 0; b < world->bodies.size(); ++b) {
    const Body& body = world->bodies[b];
    EXPECT_EQ(obj.facesPerObject[b], body.triangleCount);
    long uvEnd = uvBegin;
    for (Index f = 0; f < body.triangleCount; ++f)
      for (int k = 0; k < 3; ++k) {
        const auto& corner = obj.faces[body.firstTriangle + f][k];
        const long particle = long(world->triangles[body.firstTriangle + f][k]) + 1;
        EXPECT_EQ(corner[0], particle);
        // A body's faces use its own UVs, and the UV each corner had.
        ASSERT_GT(corner[1], uvBegin);
        ASSERT_LE(corner[1], long(obj.vt.size()));
        EXPECT_EQ(obj.vt[std::size_t(corner[1] - 1)],
                  body.render.uvs[body.render.renderTriangles[f][k]]);
        uvEnd = std::max(uvEnd, corner[1]);
        EXPECT_EQ(corner[2], particle);
      }
    uvBegin = uvEnd;
  }
  EXPECT_EQ(uvBegin, long(obj.vt.size()));
}

TEST(ObjSequenceWriter, HeaderNamesVersionFrameAndTime) {
  const auto world = makeBallsTopology({1.0f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  Frame frame = deformedFrame(world, 25);
  frame.time = 1.0;
  writer.write(frame);
  const std::string text = readFile(writer.framePath(25));
  EXPECT_EQ(text.rfind(std::string("# softbake ") + softbakeVersion() + "\n# frame 25, time 1 s\n" +
                           "mtllib balls.mtl\no ball0\nv ",
                       0),
            0u)
      << text.substr(0, 120);
}

TEST(ObjSequenceWriter, NormalsOfAStretchedOctahedronPointAlongTheAxes) {
  // Corners at (±2, 0, 0), (0, ±1, 0), (0, 0, ±1): each corner's four faces are mirror images of
  // each other across the two axes through it, so its normal is its own axis, whatever the
  // weighting, and every cross product is exact in float.
  SceneSetup setup;
  BodySetup body;
  body.name = "octahedron";
  body.mesh.positions = {Vec3f(2, 0, 0),  Vec3f(-2, 0, 0), Vec3f(0, 1, 0),
                         Vec3f(0, -1, 0), Vec3f(0, 0, 1),  Vec3f(0, 0, -1)};
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) {
        const Index x = sx > 0 ? 0 : 1, y = sy > 0 ? 2 : 3, z = sz > 0 ? 4 : 5;
        // (x, y, z) runs counter-clockwise seen from outside in the octants with an even number
        // of negative signs.
        body.mesh.triangles.push_back(sx * sy * sz > 0 ? Triangle{x, y, z} : Triangle{x, z, y});
      }
  setup.bodies.push_back(body);
  const auto world = std::make_shared<const SceneTopology>(buildSceneTopology(setup));
  ASSERT_TRUE(world->bodies[0].closed);
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "octahedron");
  Frame frame;
  frame.positions = world->restPosition;
  writer.write(frame);
  const ParsedObj obj = parseObj(readFile(writer.framePath(1)));
  ASSERT_EQ(obj.v.size(), 6u);
  ASSERT_EQ(obj.vn.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i)
    EXPECT_EQ(obj.vn[i], (obj.v[i] / obj.v[i].norm()).cast<float>())
        << "corner " << obj.v[i].transpose();
}

TEST(ObjSequenceWriter, BodyWithoutUvsWritesPositionNormalFaces) {
  SceneSetup setup;
  BodySetup body;
  body.name = "plain";
  body.mesh = makeIcosphere(1, 1.0f);
  body.mesh.uvs.clear();
  setup.bodies.push_back(body);
  const auto world = std::make_shared<const SceneTopology>(buildSceneTopology(setup));
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "plain");
  writer.write(deformedFrame(world, 1));

  const std::string text = readFile(writer.framePath(1));
  EXPECT_EQ(text.find("vt "), std::string::npos);
  const ParsedObj obj = parseObj(text);
  ASSERT_EQ(obj.faces.size(), world->triangles.size());
  for (const auto& face : obj.faces)
    for (const auto& corner : face) {
      EXPECT_EQ(corner[1], 0);
      EXPECT_EQ(corner[0], corner[2]);
    }
  EXPECT_NE(text.find(cat(" ", obj.faces[0][0][0], "//", obj.faces[0][0][0])), std::string::npos);

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(writer.framePath(1).string(), aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, 1u);
  EXPECT_EQ(scene->mMeshes[0]->mNumFaces, world->bodies[0].triangleCount);
  EXPECT_FALSE(scene->mMeshes[0]->HasTextureCoords(0));
  EXPECT_TRUE(scene->mMeshes[0]->HasNormals());
}

TEST(ObjSequenceWriter, NamesFilesByPaddedFrameNumber) {
  const auto world = makeBallsTopology({1.0f});
  ScratchDirectory dir;
  ObjSequenceWriter four(world, dir.path(), "balls");
  EXPECT_EQ(four.framePath(1), dir.path() / "obj" / "balls_0001.obj");
  EXPECT_EQ(four.framePath(240), dir.path() / "obj" / "balls_0240.obj");
  EXPECT_EQ(four.framePath(12345), dir.path() / "obj" / "balls_12345.obj");
  EXPECT_EQ(four.materialLibraryPath(), dir.path() / "obj" / "balls.mtl");
  const OutputSequence sequence = four.sequence();
  EXPECT_EQ(sequence.format, "obj");
  EXPECT_EQ(sequence.pattern, "obj/balls_####.obj");
  EXPECT_EQ(sequence.printfPattern, "obj/balls_%04d.obj");
  EXPECT_EQ(sequence.files, std::vector<std::string>{"obj/balls.mtl"});

  ObjSequenceWriter six(world, dir.path(), "balls", 6);
  EXPECT_EQ(six.framePath(7), dir.path() / "obj" / "balls_000007.obj");
  EXPECT_EQ(six.sequence().printfPattern, "obj/balls_%06d.obj");

  EXPECT_THROW(ObjSequenceWriter(world, dir.path(), "balls", 0), Error);
  EXPECT_THROW(ObjSequenceWriter(world, dir.path(), "a/b"), Error);
  EXPECT_THROW(ObjSequenceWriter(world, dir.path(), ""), Error);
  EXPECT_THROW(ObjSequenceWriter(world, dir.path(), "my scene"), Error);
}

TEST(ObjSequenceWriter, MaterialLibraryTakesTheScenesBodyColours) {
  const auto world = makeBallsTopology({1.0f, 0.8f, 0.6f});
  ScratchDirectory dir;
  // Ball 0 red, ball 1 the palette (negative red), ball 2 beyond the list: the palette.
  ObjSequenceWriter writer(world, dir.path(), "balls", 4, {Vec3f(1, 0, 0), Vec3f(-1, -1, -1)});
  const std::string library = readFile(writer.materialLibraryPath());
  EXPECT_NE(library.find("newmtl ball0\nKd 1.000 0.000 0.000\n"), std::string::npos) << library;
  ObjSequenceWriter palette(world, dir.path() / "palette", "balls");
  const std::string defaults = readFile(palette.materialLibraryPath());
  const auto kd = [](const std::string& text, const std::string& material) {
    const std::size_t at = text.find("newmtl " + material + "\nKd ");
    return at == std::string::npos ? std::string() : text.substr(at, text.find('\n', at + 15) - at);
  };
  EXPECT_EQ(kd(library, "ball1"), kd(defaults, "ball1"));
  EXPECT_EQ(kd(library, "ball2"), kd(defaults, "ball2"));
  EXPECT_NE(kd(library, "ball0"), kd(defaults, "ball0"));
}

TEST(ObjSequenceWriter, MaterialLibraryHasADistinctColourPerBody) {
  const auto world = makeBallsTopology({1.0f, 0.8f, 0.6f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  std::istringstream lines(readFile(writer.materialLibraryPath()));
  std::vector<std::string> materials;
  std::set<std::string> colours;
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("newmtl ", 0) == 0) materials.push_back(line.substr(7));
    if (line.rfind("Kd ", 0) == 0) colours.insert(line);
  }
  EXPECT_EQ(materials, (std::vector<std::string>{"ball0", "ball1", "ball2"}));
  EXPECT_EQ(colours.size(), 3u);

  Assimp::Importer importer;
  writer.write(deformedFrame(world, 1));
  const aiScene* scene = importer.ReadFile(writer.framePath(1).string(), aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    aiColor3D kd;
    scene->mMaterials[scene->mMeshes[m]->mMaterialIndex]->Get(AI_MATKEY_COLOR_DIFFUSE, kd);
    EXPECT_GT(kd.r + kd.g + kd.b, 0.5f) << "material library not read";
  }
}

TEST(ObjSequenceWriter, ObjectNamesHaveNoSpacesAndAreUnique) {
  SceneSetup setup;
  for (int i = 0; i < 2; ++i) {
    BodySetup body;
    body.name = "red ball";
    body.mesh = makeIcosphere(1, 1.0f, Vec3f(3.0f * float(i), 0, 0));
    setup.bodies.push_back(body);
  }
  const auto world = std::make_shared<const SceneTopology>(buildSceneTopology(setup));
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  writer.write(deformedFrame(world, 1));
  const ParsedObj obj = parseObj(readFile(writer.framePath(1)));
  EXPECT_EQ(obj.objects, (std::vector<std::string>{"red_ball", "red_ball_2"}));
  EXPECT_EQ(obj.materials, obj.objects);
}

TEST(ObjSequenceWriter, WritesAfterTheCallerLetGoOfTheTopology) {
  ScratchDirectory dir;
  Frame frame;
  std::unique_ptr<ObjSequenceWriter> writer;
  std::string expected;
  {
    const auto world = makeBallsTopology({1.0f, 0.5f});
    frame = deformedFrame(world, 1);
    writer = std::make_unique<ObjSequenceWriter>(world, dir.path(), "balls");
    ScratchDirectory other;
    ObjSequenceWriter reference(world, other.path(), "balls");
    reference.write(frame);
    expected = readFile(reference.framePath(1));
  }
  writer->write(frame);
  EXPECT_EQ(readFile(writer->framePath(1)), expected);
}

TEST(ObjSequenceWriter, NonFinitePositionIsRefusedNamingBodyAndFrame) {
  const auto world = makeBallsTopology({1.0f, 0.5f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  for (Scalar bad :
       {std::numeric_limits<Scalar>::quiet_NaN(), std::numeric_limits<Scalar>::infinity()}) {
    Frame frame = deformedFrame(world, 7);
    frame.positions[world->bodies[1].firstParticle + 5].y() = bad;
    try {
      writer.write(frame);
      FAIL() << "expected softbake::Error";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("frame 7"), std::string::npos) << message;
      EXPECT_NE(message.find("'ball1'"), std::string::npos) << message;
    }
  }
  EXPECT_EQ(listDirectory(dir.path() / "obj"), std::vector<std::string>{"balls.mtl"});
}

TEST(ObjSequenceWriter, FailedWriteLeavesNoFileAndNamesIt) {
  const auto world = makeBallsTopology({1.0f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  std::filesystem::create_directory(writer.framePath(2));
  writer.write(deformedFrame(world, 1));
  try {
    writer.write(deformedFrame(world, 2));
    FAIL() << "expected softbake::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(writer.framePath(2).string()), std::string::npos);
  }
  EXPECT_EQ(listDirectory(dir.path() / "obj"),
            (std::vector<std::string>{"balls.mtl", "balls_0001.obj", "balls_0002.obj"}));
  EXPECT_TRUE(std::filesystem::is_directory(writer.framePath(2)));
}

TEST(ObjSequenceWriter, CountsTheBytesItWrote) {
  const auto world = makeBallsTopology({1.0f, 0.5f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  for (int n = 1; n <= 3; ++n) writer.write(deformedFrame(world, n));
  std::uint64_t onDisk = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path() / "obj"))
    onDisk += entry.file_size();
  EXPECT_EQ(writer.bytesWritten(), onDisk);
}

TEST(ObjSequenceWriter, WrongParticleCountIsAnError) {
  const auto world = makeBallsTopology({1.0f});
  ScratchDirectory dir;
  ObjSequenceWriter writer(world, dir.path(), "balls");
  Frame frame = deformedFrame(world, 1);
  frame.positions.pop_back();
  EXPECT_THROW(writer.write(frame), Error);
}

}  // namespace
}  // namespace softbake
