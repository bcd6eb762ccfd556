// The fuzz targets' entry functions (fuzz/fuzz_entries.hpp), run by the ordinary suite: every
// seed scripts/fuzz.sh starts from must load, and every input that ever crashed a target
// (tests/data/fuzz/<target>/) must now end in a clear error or a load.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "fuzz/fuzz_entries.hpp"

namespace softbake::fuzz {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = SOFTBAKE_SOURCE_DIR;

std::string bytesOf(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  EXPECT_TRUE(in) << "cannot read " << file;
  return {std::istreambuf_iterator<char>(in), {}};
}

// The files (or the folders) in `folder`, sorted; a missing or empty folder fails the test.
std::vector<fs::path> entriesIn(const fs::path& folder, bool folders) {
  std::vector<fs::path> found;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error))
    if (folders ? entry.is_directory() : entry.is_regular_file()) found.push_back(entry.path());
  std::sort(found.begin(), found.end());
  EXPECT_FALSE(found.empty()) << "nothing in " << folder;
  return found;
}
std::vector<fs::path> filesIn(const fs::path& folder) {
  return entriesIn(folder, false);
}
std::vector<fs::path> foldersIn(const fs::path& folder) {
  return entriesIn(folder, true);
}

// The input of the mesh target for `file`: its format byte, then the file.
std::string meshInput(const fs::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return meshFormatByte(extension) + bytesOf(file);
}

TEST(FuzzSeeds, EveryExampleSceneLoadsAndBuildsThroughTheSceneTarget) {
  for (const fs::path& file : filesIn(kSource / "examples")) {
    if (file.extension() != ".json") continue;
    EXPECT_EQ(sceneText(bytesOf(file)), Outcome::kLoaded) << file;
  }
}

TEST(FuzzSeeds, EveryPlySeedPassesTheGuard) {
  std::vector<fs::path> files = filesIn(kSource / "fuzz" / "seeds" / "ply");
  files.push_back(kSource / "tests" / "data" / "meshes" / "fuze.ply");
  for (const fs::path& file : files) EXPECT_EQ(plyGuard(bytesOf(file)), Outcome::kLoaded) << file;
}

TEST(FuzzSeeds, EveryMeshSeedImportsFromMemoryAndBuildsAWorld) {
  const fs::path meshes = kSource / "tests" / "data" / "meshes";
  std::vector<fs::path> files = filesIn(kSource / "fuzz" / "seeds" / "meshes");
  for (const fs::path& file : filesIn(kSource / "fuzz" / "seeds" / "ply")) files.push_back(file);
  for (const char* name : {"ico4.obj", "fuze.ply", "sphereWithHole.stl", "torus.STL",
                           "cubes_with_mirroring_and_pivot.fbx"})
    files.push_back(meshes / name);
  files.push_back(kSource / "tests" / "data" / "import" / "box.gltf");
  files.push_back(kSource / "tests" / "data" / "import" / "box.glb");
  for (const fs::path& file : files)
    EXPECT_EQ(meshImport(meshInput(file)), Outcome::kLoaded) << file;
}

// The truncated PLY that makes assimp 5.2 segfault is a seed of both PLY-reading targets: the
// guard must refuse it before assimp sees it, or this test process dies.
TEST(FuzzSeeds, TheAssimpCrashingPlyIsRefusedByBothTargets) {
  const fs::path crash = kSource / "tests" / "data" / "meshes" / "broken" /
                         "crash-30d6d0f7c529b3b66b4131700b7a4580cd7082df.ply";
  EXPECT_EQ(plyGuard(bytesOf(crash)), Outcome::kRefused);
  EXPECT_EQ(meshImport(meshInput(crash)), Outcome::kRefused);
}

// Each file under tests/data/fuzz/<target>/ crashed that target once (fuzz/README.md says how
// and what was fixed); the entry function now refuses or loads it. A crash brings the test down;
// an exception other than softbake::Error (a FuzzFinding) fails it here.
TEST(FuzzFindings, EveryInputThatOnceCrashedATargetNowEndsWell) {
  const std::map<std::string, Outcome (*)(std::string_view)> entries = {
      {"scene", sceneText}, {"ply_guard", plyGuard}, {"mesh_import", meshImport}};
  std::size_t inputs = 0;
  for (const fs::path& folder : foldersIn(kSource / "tests" / "data" / "fuzz")) {
    const auto entry = entries.find(folder.filename().string());
    ASSERT_NE(entry, entries.end()) << folder << " is no fuzz target's";
    for (const fs::path& file : filesIn(folder)) {
      ++inputs;
      try {
        entry->second(bytesOf(file));
      } catch (const std::exception& finding) {
        ADD_FAILURE() << file << ": " << finding.what();
      }
    }
  }
  EXPECT_GT(inputs, 0u);
}

}  // namespace
}  // namespace softbake::fuzz
