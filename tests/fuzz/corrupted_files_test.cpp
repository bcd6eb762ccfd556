// 200 seeded random truncations and bit flips of every good test file of the formats users bring
// (OBJ, PLY, STL, glTF, GLB, FBX), each imported as `softbake run FILE` imports it: import, the
// scene of its meshes, world building. Each must end in a clear error (softbake::Error naming the
// file) or a load that holds together (fuzz::checkWorld); never a crash, a hang or memory without
// bound. assimp reads in a child process (importers/assimp_snapshot.hpp), so a crash inside
// assimp is one of the clear errors; a crash in softbake's own code takes this test down. So is
// a reading that hangs: the import time limit kills the child and names the file (enforced there,
// tested through its hook in import_limits_test and import_cli_test), and such files are counted
// here. How long an import takes is no result: a hang in softbake's own code is the ctest
// timeout's to catch.
//
// A sample of the refused files also goes through the `softbake` binary: exit status 1, a message
// naming the file, and no frame written.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/resource.h>

#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/scene/scene_topology.hpp"
#include "fuzz/fuzz_entries.hpp"
#include "importers/scene_file.hpp"
#include "tests/cli/softbake_process.hpp"
#include "tests/support/scratch_directory.hpp"

namespace softbake {
namespace {

namespace fs = std::filesystem;

constexpr int kMutations = 200;
// Refused files per good file that also go through the binary (a process start each).
constexpr int kThroughTheBinary = 4;
constexpr std::uint64_t kImportMemoryMib = 512;

struct GoodFile {
  const char* path;                 ///< relative to the source folder
  std::vector<const char*> beside;  ///< companions copied next to each mutation
};

// gtest prints a parameter by its bytes otherwise.
void PrintTo(const GoodFile& file, std::ostream* out) {
  *out << file.path;
}

const fs::path kSource = SOFTBAKE_SOURCE_DIR;

const GoodFile kGoodFiles[] = {
    {"tests/data/meshes/ico4.obj", {"tests/data/meshes/ico4.mtl"}},
    {"fuzz/seeds/meshes/cube.obj", {}},
    {"tests/data/meshes/fuze.ply", {}},
    {"fuzz/seeds/ply/strips_ascii.ply", {}},
    {"tests/data/meshes/torus.STL", {}},
    {"tests/data/meshes/sphereWithHole.stl", {}},
    {"tests/data/import/box.gltf", {}},
    {"tests/data/meshes/AnimatedMorphSphere.gltf", {"tests/data/meshes/AnimatedMorphSphere.bin"}},
    {"tests/data/import/box.glb", {}},
    {"tests/data/meshes/cubes_with_mirroring_and_pivot.fbx", {}},
    {"fuzz/seeds/meshes/cube_ascii.fbx", {}},
};

std::string bytesOf(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  EXPECT_TRUE(in) << "cannot read " << file;
  return {std::istreambuf_iterator<char>(in), {}};
}

void writeBytes(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// Even mutations cut the file at a random length, odd ones flip 1 to 8 random bits.
std::string mutate(const std::string& good, int mutation, std::mt19937_64& random) {
  std::string bytes = good;
  if (mutation % 2 == 0) {
    bytes.resize(std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(random));
  } else {
    const int flips = std::uniform_int_distribution<int>(1, 8)(random);
    for (int f = 0; f < flips; ++f) {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(random);
      bytes[at] = char(bytes[at] ^ (1 << std::uniform_int_distribution<int>(0, 7)(random)));
    }
  }
  return bytes;
}

std::uint64_t peakKib(int who) {
  rusage usage{};
  getrusage(who, &usage);
  return std::uint64_t(usage.ru_maxrss);
}

class CorruptedFiles : public ::testing::TestWithParam<GoodFile> {};

TEST_P(CorruptedFiles, EndInAClearErrorOrASoundLoad) {
  const fs::path good = kSource / GetParam().path;
  const std::string original = bytesOf(good);
  ASSERT_FALSE(original.empty());
  test::ScratchDirectory dir;
  for (const char* companion : GetParam().beside)
    fs::copy_file(kSource / companion, dir.path() / fs::path(companion).filename());
  const fs::path file = dir.path() / good.filename();

  SceneLoadOptions options;
  options.maxImportMemoryMib = kImportMemoryMib;
  // The same seed every run, a different one per file.
  std::mt19937_64 random(std::hash<std::string>()(GetParam().path));
  int refused = 0, loaded = 0, assimpCrashes = 0, pastTheTimeLimit = 0, throughTheBinary = 0;
  for (int mutation = 0; mutation < kMutations; ++mutation) {
    writeBytes(file, mutate(original, mutation, random));
    SCOPED_TRACE(testing::Message() << "mutation " << mutation << " of " << good.filename());
    bool isRefused = false;
    try {
      const SceneFile scene = sceneFromMeshFile(file, options);
      fuzz::checkWorld(buildSceneTopology(scene.setup));
      ++loaded;
    } catch (const Error& error) {
      isRefused = true;
      ++refused;
      const std::string message = error.what();
      if (message.find(": assimp crashed reading the file") != std::string::npos) ++assimpCrashes;
      if (message.find(": reading the file took longer than the import time limit") !=
          std::string::npos)
        ++pastTheTimeLimit;
      // World building names the body, and the body is named after the file.
      EXPECT_TRUE(message.starts_with(file.string()) ||
                  message.starts_with("body '" + file.stem().string()))
          << message;
    }

    if (isRefused && throughTheBinary < kThroughTheBinary) {
      ++throughTheBinary;
      const fs::path out = dir.path() / "out";
      const test::Result run = test::runSoftbake(
          "run " + test::quoted(file) + " --frames 2 --no-render -q -o " + test::quoted(out) +
          " --max-import-memory " + std::to_string(kImportMemoryMib));
      EXPECT_EQ(run.exitCode, 1) << run.output;
      EXPECT_NE(run.output.find("softbake: error: "), std::string::npos) << run.output;
      EXPECT_NE(run.output.find(file.filename().string()), std::string::npos) << run.output;
      EXPECT_FALSE(fs::exists(out / "obj")) << "frames written for a refused file";
      fs::remove_all(out);
    }
  }
  EXPECT_EQ(refused + loaded, kMutations);
  // Bounded memory: this process and the largest of the children that read with assimp.
  EXPECT_LT(peakKib(RUSAGE_SELF), 1'500'000u);
  EXPECT_LT(peakKib(RUSAGE_CHILDREN), 1'500'000u);
  RecordProperty("refused", refused);
  RecordProperty("loaded", loaded);
  // Files that crashed assimp in its child process, or kept it reading until the time limit, for
  // the record (fuzz/README.md).
  RecordProperty("assimp_crashes", assimpCrashes);
  RecordProperty("past_the_import_time_limit", pastTheTimeLimit);
}

INSTANTIATE_TEST_SUITE_P(GoodFiles, CorruptedFiles, ::testing::ValuesIn(kGoodFiles),
                         [](const auto& test) {
                           std::string name = fs::path(test.param.path).filename().string();
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace softbake
