// A user's own file, as the user sees it: pins.indices number the file's vertices (not softbake's
// particles), and the OBJ export keeps the file's UVs, each once.

#include <gtest/gtest.h>

#include <charconv>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/text.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "importers/scene_file.hpp"
#include "test_files.hpp"
#include "tests/support/obj_text.hpp"

namespace softbake {
namespace {

// A 3×3 grid of points 0.5 apart, split into two objects (the columns of cells x < 1 and x > 1).
// The `v` statements list the points backwards, so the file's order is not the order in which
// faces first use them (the particle order). The column on x = 0.5 is a UV seam: its points
// have one UV in each object. The first vt is listed twice, the copy used by one corner, and one
// vt is used by no face: 14 vt statements, 12 distinct UVs in use.
struct GridObj {
  std::string text;
  std::vector<Vec3f> v;                     ///< the file's vertices, in file order
  std::vector<Vec2f> vt;                    ///< the file's UVs, in file order
  std::vector<std::array<int, 6>> corners;  ///< per triangle: v, vt (0-based) of its 3 corners
};

GridObj gridObj() {
  GridObj obj;
  auto fileIndex = [](int x, int z) { return 8 - (z * 3 + x); };
  obj.v.resize(9);
  for (int z = 0; z < 3; ++z)
    for (int x = 0; x < 3; ++x)
      obj.v[std::size_t(fileIndex(x, z))] = Vec3f(0.5f * float(x), 0, 0.5f * float(z));
  // vt of point (x, z) in column c: columns are 0.5 apart in u.
  auto uvIndex = [](int column, int x, int z) { return column * 6 + (x - column) * 3 + z; };
  for (int column = 0; column < 2; ++column)
    for (int x = column; x < column + 2; ++x)
      for (int z = 0; z < 3; ++z)
        obj.vt.push_back(Vec2f(0.5f * float(column) + 0.25f * float(x - column), 0.5f * float(z)));
  obj.vt.push_back(obj.vt[0]);            // 12: the copy
  obj.vt.push_back(Vec2f(0.75f, 0.75f));  // 13: unused
  std::ostringstream text;
  text << "# grid\n";
  for (const Vec3f& p : obj.v) text << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const Vec2f& uv : obj.vt) text << "vt " << uv.x() << ' ' << uv.y() << '\n';
  for (int column = 0; column < 2; ++column) {
    text << "o column" << column << '\n';
    for (int z = 0; z < 2; ++z) {
      const int x = column;
      const std::array<std::array<int, 2>, 4> quad = {
          {{x, z}, {x, z + 1}, {x + 1, z + 1}, {x + 1, z}}};
      for (const std::array<int, 3>& triangle : {std::array<int, 3>{0, 1, 2}, {0, 2, 3}}) {
        std::array<int, 6> corner{};
        text << 'f';
        for (int k = 0; k < 3; ++k) {
          const auto [px, pz] = quad[std::size_t(triangle[std::size_t(k)])];
          int uv = uvIndex(column, px, pz);
          if (column == 0 && z == 0 && triangle[1] == 2 && k == 0) uv = 12;
          corner[std::size_t(2 * k)] = fileIndex(px, pz);
          corner[std::size_t(2 * k + 1)] = uv;
          text << ' ' << fileIndex(px, pz) + 1 << '/' << uv + 1;
        }
        text << '\n';
        obj.corners.push_back(corner);
      }
    }
  }
  obj.text = text.str();
  return obj;
}

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

SceneFile parse(const std::string& text, const std::filesystem::path& base) {
  return parseScene(nlohmann::json::parse(text), "scene.json", base);
}

std::string sceneError(const std::string& text, const std::filesystem::path& base) {
  try {
    parse(text, base);
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

std::vector<Vec3> pinnedPositions(const SceneFile& scene) {
  const SceneTopology topology = buildSceneTopology(scene.setup);
  std::vector<Vec3> pinned;
  for (std::size_t i = 0; i < topology.particleCount(); ++i)
    if (topology.inverseMass[i] == 0) pinned.push_back(topology.restPosition[i]);
  return pinned;
}

TEST(PinsByFileIndex, PinTheFilesVertexOfAnObjWhoseOrderIsNotTheParticles) {
  test::ScratchDir dir;
  const GridObj obj = gridObj();
  dir.write("grid.obj", obj.text);
  const SceneFile scene = parse(R"({"bodies": [{"mesh": "grid.obj", "merge_meshes": true,
      "transform": {"translate": [0, 1, 0]}, "pins": {"indices": [0]}}]})",
                                dir.path());
  const SceneTopology topology = buildSceneTopology(scene.setup);
  ASSERT_EQ(topology.particleCount(), 9u);
  // The test means something only where particle 0 is not the file's vertex 0.
  ASSERT_NE(topology.restPosition[0], (obj.v[0] + Vec3f(0, 1, 0)).cast<Scalar>());

  for (std::size_t vertex = 0; vertex < obj.v.size(); ++vertex) {
    const SceneFile one = parse(cat(R"({"bodies": [{"mesh": "grid.obj", "merge_meshes": true,
        "transform": {"translate": [0, 1, 0]}, "pins": {"indices": [)",
                                    vertex, "]}}]}"),
                                dir.path());
    const std::vector<Vec3> pinned = pinnedPositions(one);
    ASSERT_EQ(pinned.size(), 1u) << "vertex " << vertex;
    EXPECT_EQ(pinned[0], (obj.v[vertex] + Vec3f(0, 1, 0)).cast<Scalar>()) << "vertex " << vertex;
  }
}

TEST(PinsByFileIndex, ParticlesStayAvailableUnderTheirOwnKey) {
  test::ScratchDir dir;
  dir.write("grid.obj", gridObj().text);
  const SceneFile scene = parse(
      R"({"bodies": [{"mesh": "grid.obj", "merge_meshes": true, "pins": {"particles": [0, 4]}}]})",
      dir.path());
  const SceneTopology topology = buildSceneTopology(scene.setup);
  const std::vector<Vec3> pinned = pinnedPositions(scene);
  EXPECT_EQ(pinned, (std::vector<Vec3>{topology.restPosition[0], topology.restPosition[4]}));
}

TEST(PinsByFileIndex, AnOffFileNumbersItsVertexList) {
  const std::filesystem::path off = test::testMeshes() / "ballA.off";
  std::istringstream lines(readText(off));
  std::string line;
  std::getline(lines, line);  // OFF
  std::getline(lines, line);  // counts
  std::vector<Vec3f> vertices;
  for (int i = 0; i < 1000 && std::getline(lines, line); ++i) {
    std::istringstream numbers(line);
    Vec3f p;
    numbers >> p.x() >> p.y() >> p.z();
    vertices.push_back(p);
  }
  for (std::size_t vertex : {0u, 1u, 517u, 999u}) {
    const std::vector<Vec3> pinned =
        pinnedPositions(parse(cat(R"({"bodies": [{"mesh": ")", off.string(),
                                  R"(", "pins": {"indices": [)", vertex, "]}}]}"),
                              {}));
    ASSERT_EQ(pinned.size(), 1u) << "vertex " << vertex;
    // The test reads with the C library, assimp with its own parser: the last bit may differ.
    EXPECT_TRUE(pinned[0].cast<float>().isApprox(vertices[vertex], 1e-6f))
        << "vertex " << vertex << ": " << pinned[0].transpose();
  }
}

TEST(PinsByFileIndex, AnIndexPastTheFileNamesTheSceneTheKeyTheFileAndItsCount) {
  test::ScratchDir dir;
  dir.write("grid.obj", gridObj().text);
  EXPECT_EQ(sceneError(R"({"bodies": [{"mesh": "grid.obj", "merge_meshes": true,
                           "pins": {"indices": [3, 9]}}]})",
                       dir.path()),
            "scene.json: bodies[0].pins.indices[1]: vertex 9 is beyond the 9 vertices of grid.obj "
            "(indices count from 0)");
  EXPECT_EQ(sceneError(R"({"bodies": [{"mesh": "grid.obj", "merge_meshes": true,
                           "pins": {"particles": [100000]}}]})",
                       dir.path()),
            "scene.json: bodies[0].pins.particles[0]: particle 100000 is beyond the 9 particles of "
            "grid.obj (indices count from 0)");
  EXPECT_EQ(
      sceneError(R"({"bodies": [{"mesh": "grid.obj", "pins": {"indices": [0]}}]})", dir.path()),
      "scene.json: bodies[0].pins.indices: vertex indices need a single mesh, but the file "
      "gives 2; set merge_meshes to true or pin with boxes");
}

TEST(PinsByFileIndex, AFormatWithoutAKnownNumberingIsRefusedByName) {
  const std::filesystem::path fbx = test::testMeshes() / "cubes_with_mirroring_and_pivot.fbx";
  const std::string message =
      sceneError(cat(R"({"bodies": [{"mesh": ")", fbx.string(),
                     R"(", "merge_meshes": true, "pins": {"indices": [0]}}]})"),
                 {});
  EXPECT_EQ(message.rfind(cat("scene.json: bodies[0].pins.indices: ", fbx.string(),
                              ": softbake knows the vertex numbering of OBJ"),
                          0),
            0u)
      << message;
}

/// The `v`, `vt` and `f` statements of an OBJ softbake wrote (triangles, v/vt/vn).
TEST(ObjExportOfAUvMesh, WritesEachDistinctUvOnceAndEveryCornerTheFilesUv) {
  test::ScratchDir dir;
  const GridObj input = gridObj();
  dir.write("grid.obj", input.text);
  const SceneFile scene =
      parse(R"({"bodies": [{"mesh": "grid.obj", "merge_meshes": true}]})", dir.path());
  const auto topology = std::make_shared<const SceneTopology>(buildSceneTopology(scene.setup));
  ObjSequenceWriter writer(topology, dir / "out", "grid");
  Frame frame;
  frame.number = 1;
  frame.positions = topology->restPosition;
  writer.write(frame);
  const test::ParsedObj output = test::parseObj(readText(writer.framePath(1)));

  std::set<std::pair<float, float>> distinct;
  for (const auto& corners : input.corners)
    for (int k = 0; k < 3; ++k) {
      const Vec2f& uv = input.vt[std::size_t(corners[std::size_t(2 * k + 1)])];
      distinct.insert({uv.x(), uv.y()});
    }
  ASSERT_EQ(distinct.size(), 12u);
  EXPECT_EQ(output.vt.size(), distinct.size());

  // Each written face is one of the file's, found by its corners' positions; its corners carry
  // the UVs the file gave them.
  std::map<std::set<std::array<float, 3>>, std::size_t> inputFace;
  auto key = [](const Vec3f& p) { return std::array<float, 3>{p.x(), p.y(), p.z()}; };
  for (std::size_t t = 0; t < input.corners.size(); ++t) {
    std::set<std::array<float, 3>> positions;
    for (int k = 0; k < 3; ++k)
      positions.insert(key(input.v[std::size_t(input.corners[t][std::size_t(2 * k)])]));
    inputFace[positions] = t;
  }
  ASSERT_EQ(output.faces.size(), input.corners.size());
  std::set<std::size_t> seen;
  for (const auto& face : output.faces) {
    std::set<std::array<float, 3>> positions;
    for (const auto& corner : face) {
      ASSERT_GE(corner[0], 1);
      ASSERT_LE(corner[0], long(output.v.size()));
      positions.insert(key(output.v[std::size_t(corner[0] - 1)]));
    }
    const auto found = inputFace.find(positions);
    ASSERT_NE(found, inputFace.end());
    seen.insert(found->second);
    const std::array<int, 6>& corners = input.corners[found->second];
    for (const auto& corner : face) {
      ASSERT_GE(corner[1], 1);
      ASSERT_LE(corner[1], long(output.vt.size()));
      const Vec3f& p = output.v[std::size_t(corner[0] - 1)];
      int k = 0;
      while (k < 3 && input.v[std::size_t(corners[std::size_t(2 * k)])] != p) ++k;
      ASSERT_LT(k, 3);
      EXPECT_EQ(output.vt[std::size_t(corner[1] - 1)],
                input.vt[std::size_t(corners[std::size_t(2 * k + 1)])])
          << "at " << p.transpose();
    }
  }
  EXPECT_EQ(seen.size(), input.corners.size());
}

}  // namespace
}  // namespace softbake
