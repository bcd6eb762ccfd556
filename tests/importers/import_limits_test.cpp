// Caps on what one mesh file may bring in and on how many bodies a scene may have: each refusal
// names the file (or the scene's key) and says how to raise the cap. The time and memory limits
// hold the process that reads a file with assimp (assimp_snapshot.hpp).

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <memory>
#include <new>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/assimp_snapshot.hpp"
#include "importers/memory_budget.hpp"
#include "importers/mesh_import.hpp"
#include "importers/scene_file.hpp"
#include "test_files.hpp"
#include "tests/support/scoped_environment.hpp"

namespace softbake {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::filesystem::path box() {
  return test::sourceDir() / "tests" / "data" / "import" / "box.gltf";
}

template <class Load>
std::string errorOf(Load&& load) {
  try {
    load();
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

SceneFile sceneOf(const std::string& json, const SceneLoadOptions& options = {}) {
  return parseScene(nlohmann::json::parse(json), "scene.json", ".", options);
}

// A reader that waits instead of reading: a file that takes assimp long. A minute at most, so a
// build that reads in this process (ThreadSanitizer) fails instead of hanging.
const aiScene* waitingRead(Assimp::Importer&, unsigned) {
  std::this_thread::sleep_for(std::chrono::seconds(60));
  return nullptr;
}

// A reader that maps memory until it finds none: a file that asks assimp for ever more. 4 GiB at
// most, untouched, so a build that reads in this process fails instead of taking the machine.
const aiScene* greedyRead(Assimp::Importer&, unsigned) {
  std::vector<std::unique_ptr<char[]>> blocks;
  for (int block = 0; block < 64; ++block) {
    blocks.emplace_back(new char[std::size_t(64) << 20]);
    blocks.back()[0] = 1;
  }
  return nullptr;
}

// The same, as assimp's readers do it: the std::bad_alloc becomes the reader's error.
const aiScene* greedyCatchingRead(Assimp::Importer& importer, unsigned flags) {
  try {
    greedyRead(importer, flags);
  } catch (const std::bad_alloc&) {
  }
  return nullptr;
}

using TestImports = test::ScopedEnvironment;

TEST(ImportLimits, FacesAndVerticesAboveTheirCapsAreRefusedNamingTheFile) {
  ImportLimits limits;
  limits.maxFaces = 11;
  EXPECT_EQ(errorOf([&] { importMeshFile(box(), {.limits = limits}); }),
            box().string() +
                ": 12 faces, above the limit of 11 per file (--max-faces or "
                "settings.import.max_faces raises it)");
  limits.maxFaces = 12;
  limits.maxVertices = 7;
  EXPECT_EQ(errorOf([&] { importMeshFile(box(), {.limits = limits}); }),
            box().string() +
                ": 8 vertices, above the limit of 7 per file (--max-vertices or "
                "settings.import.max_vertices raises it)");
  limits.maxVertices = 8;
  EXPECT_EQ(importMeshFile(box(), {.limits = limits}).meshes[0].triangles.size(), 12u);
}

TEST(ImportLimits, APlyHeaderAboveTheDefaultCapIsRefusedBeforeItsRowsAreRead) {
  test::ScratchDir dir;
  const auto file = dir.write("huge.ply",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                              "property float y\nproperty float z\nelement face 60000000\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(errorOf([&] { importMeshFile(file, {.acceptLossy = true}); }),
            file.string() +
                ": 60000000 faces, above the limit of 50000000 per file (--max-faces or "
                "settings.import.max_faces raises it)");
}

TEST(ImportLimits, MemoryAboveTheCapIsRefusedNamingTheCap) {
  ImportLimits limits;
  limits.maxMemoryBytes = 1024;  // the file alone is 1091 bytes
  EXPECT_EQ(errorOf([&] { importMeshFile(box(), {.limits = limits}); }),
            box().string() +
                ": reading the file needs about 1.1 KiB, above the import memory limit of 1.0 "
                "KiB (--max-import-memory or settings.import.max_memory_mib raises it)");
}

TEST(ImportLimits, TheSceneSetsTheCapsAndTheCommandLineWins) {
  const std::string scene =
      cat(R"({"settings": {"import": {"max_faces": 11}}, "bodies": [{"mesh": ")", box().string(),
          R"("}]})");
  EXPECT_THAT(errorOf([&] { sceneOf(scene); }),
              StartsWith("scene.json: bodies[0].mesh: " + box().string() +
                         ": 12 faces, above the limit of 11 per file"));
  EXPECT_EQ(sceneOf(scene, {.maxFaces = 12}).setup.bodies.size(), 1u);
  EXPECT_THAT(
      errorOf([&] { sceneOf(R"({"settings": {"import": {"max_memory_mib": 0}}, "bodies": []})"); }),
      StartsWith("scene.json: settings.import.max_memory_mib: expected an integer in [1, "));
}

TEST(ImportLimits, EveryImportHasATimeAndAMemoryLimitByDefault) {
  EXPECT_EQ(ImportLimits().maxSeconds, 120u);
  EXPECT_EQ(importMemoryBytes({}), physicalMemoryBytes() / 2);
  EXPECT_EQ(importMemoryBytes({.maxMemoryBytes = 1024}), 1024u);
  EXPECT_EQ(importMemoryLimitMessage("a.iqm", {}),
            cat("a.iqm: reading the file took more memory than the import memory limit of ",
                formatBytes(double(physicalMemoryBytes() / 2)),
                ", half of this machine's memory (--max-import-memory or "
                "settings.import.max_memory_mib raises it)"));
}

TEST(ImportLimits, AReadingPastTheTimeLimitIsKilledNamingTheLimit) {
  EXPECT_EQ(
      errorOf([] { takeAssimpSnapshotInChild(waitingRead, 0, "slow.obj", {.maxSeconds = 1}); }),
      "slow.obj: reading the file took longer than the import time limit of 1 s "
      "(--max-import-seconds or settings.import.max_seconds raises it)");
  // The killed child was reaped: this process has no child left, not even a zombie.
  errno = 0;
  EXPECT_EQ(::waitpid(-1, nullptr, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
}

TEST(ImportLimits, TheSceneSetsTheTimeLimitAndTheCommandLineWins) {
  const TestImports stalled("SOFTBAKE_TEST_IMPORT_STALL_SECONDS", "60");
  const std::string scene =
      cat(R"({"settings": {"import": {"max_seconds": 1}}, "bodies": [{"mesh": ")", box().string(),
          R"("}]})");
  EXPECT_EQ(errorOf([&] { sceneOf(scene); }),
            "scene.json: bodies[0].mesh: " + box().string() +
                ": reading the file took longer than the import time limit of 1 s "
                "(--max-import-seconds or settings.import.max_seconds raises it)");
  EXPECT_THAT(errorOf([&] { sceneOf(scene, {.maxImportSeconds = 2}); }),
              HasSubstr(": reading the file took longer than the import time limit of 2 s "));
  EXPECT_THAT(
      errorOf([&] { sceneOf(R"({"settings": {"import": {"max_seconds": 0}}, "bodies": []})"); }),
      StartsWith("scene.json: settings.import.max_seconds: expected an integer in [1, "));
}

TEST(ImportLimits, AnAllocationPastTheMemoryLimitFailsNamingTheLimit) {
  const ImportLimits limits{.maxMemoryBytes = std::uint64_t(256) << 20};
  const std::string message =
      "greedy.obj: reading the file took more memory than the import memory limit of 256.0 MiB "
      "(--max-import-memory or settings.import.max_memory_mib raises it)";
  EXPECT_EQ(errorOf([&] { takeAssimpSnapshotInChild(greedyRead, 0, "greedy.obj", limits); }),
            message);
  EXPECT_EQ(
      errorOf([&] { takeAssimpSnapshotInChild(greedyCatchingRead, 0, "greedy.obj", limits); }),
      message);
  // The limit is on what the reading adds to the process: an ordinary file reads well within it.
  EXPECT_EQ(importMeshFile(box(), {.limits = limits}).meshes.at(0).triangles.size(), 12u);
}

// Past what the machine can give, before the limit: the kernel's out-of-memory killer ends the
// reading with SIGKILL, which softbake did not send.
TEST(ImportLimits, AReadingKilledByTheSystemIsSaidToHaveLackedMemory) {
  const AssimpRead killed = [](Assimp::Importer&, unsigned) -> const aiScene* {
    ::raise(SIGKILL);
    return nullptr;
  };
  EXPECT_EQ(errorOf([&] {
              takeAssimpSnapshotInChild(killed, 0, "big.obj",
                                        {.maxMemoryBytes = std::uint64_t(1) << 30});
            }),
            "big.obj: the process reading the file was killed (Killed), most likely by the system "
            "for lack of memory: the import memory limit of 1.0 GiB is more than this machine "
            "could give it (--max-import-memory or settings.import.max_memory_mib lowers it)");
}

TEST(ImportLimits, TheSceneSetsTheMemoryLimitOfTheReadingAndTheCommandLineWins) {
  const TestImports allocating("SOFTBAKE_TEST_IMPORT_ALLOCATE_MIB", "1024");
  const std::string scene =
      cat(R"({"settings": {"import": {"max_memory_mib": 256}}, "bodies": [{"mesh": ")",
          box().string(), R"("}]})");
  EXPECT_EQ(errorOf([&] { sceneOf(scene); }),
            "scene.json: bodies[0].mesh: " + box().string() +
                ": reading the file took more memory than the import memory limit of 256.0 MiB "
                "(--max-import-memory or settings.import.max_memory_mib raises it)");
  EXPECT_THAT(errorOf([&] { sceneOf(scene, {.maxImportMemoryMib = 128}); }),
              HasSubstr(": reading the file took more memory than the import memory limit of "
                        "128.0 MiB "));
  EXPECT_EQ(sceneOf(scene, {.maxImportMemoryMib = 2048}).setup.bodies.size(), 1u);
}

// Found by fuzzing: a few lines asking for many finely subdivided spheres took all the memory
// there was. The scene's meshes together stay within the caps of one file, counted before each
// primitive is made.
TEST(ImportLimits, TheWholeScenesMeshesStayWithinTheCaps) {
  const std::string body = R"({"mesh": {"primitive": "icosphere", "subdivisions": 7}})";
  const std::string two = cat(R"({"bodies": [)", body, ",", body, "]}");
  EXPECT_EQ(errorOf([&] { sceneOf(two, {.maxFaces = 400'000}); }),
            "scene.json: bodies[1].mesh: the scene's meshes come to 655360 triangles, above the "
            "limit of 400000 (--max-faces or settings.import.max_faces raises it)");
  EXPECT_EQ(errorOf([&] { sceneOf(two, {.maxVertices = 300'000}); }),
            "scene.json: bodies[1].mesh: the scene's meshes come to 327684 vertices, above the "
            "limit of 300000 (--max-vertices or settings.import.max_vertices raises it)");
  EXPECT_EQ(sceneOf(two, {.maxFaces = 655'360}).setup.bodies.size(), 2u);
  // Files count too: the box has 12 triangles.
  const std::string boxes = cat(R"({"bodies": [{"mesh": ")", box().string(), R"("}, {"mesh": ")",
                                box().string(), R"("}]})");
  EXPECT_THAT(errorOf([&] { sceneOf(boxes, {.maxFaces = 20}); }),
              StartsWith("scene.json: bodies[1].mesh: the scene's meshes come to 24 triangles"));
}

TEST(ImportLimits, TooManyBodiesAreRefusedBeforeAnyMeshIsRead) {
  // The mesh files do not exist: the count is checked first.
  const std::string scene =
      R"({"bodies": [{"mesh": "a.obj"}, {"mesh": "b.obj"}, {"mesh": "c.obj"}]})";
  EXPECT_EQ(errorOf([&] { sceneOf(scene, {.maxBodies = 2}); }),
            "scene.json: bodies: 3 bodies, above the limit of 2 (--max-bodies raises it)");
  EXPECT_THAT(errorOf([&] { sceneOf(scene, {.maxBodies = 3}); }), HasSubstr("mesh file not found"));
}

TEST(ImportLimits, AFileSplitIntoMoreBodiesThanTheLimitIsRefused) {
  test::ScratchDir dir;
  std::string obj;
  for (int part = 0; part < 3; ++part)
    obj += cat("o part", part, "\nv ", part, " 0 0\nv ", part + 1, " 0 0\nv ", part, " 1 0\nf ",
               3 * part + 1, " ", 3 * part + 2, " ", 3 * part + 3, "\n");
  const auto file = dir.write("parts.obj", obj);
  const std::string scene = cat(R"({"bodies": [{"mesh": ")", file.string(), R"("}]})");
  EXPECT_EQ(errorOf([&] { sceneOf(scene, {.maxBodies = 2}); }),
            "scene.json: bodies[0]: its file's meshes bring the scene to 3 bodies, above the "
            "limit of 2 (--max-bodies raises it)");
  EXPECT_EQ(sceneOf(scene, {.maxBodies = 3}).setup.bodies.size(), 3u);
  EXPECT_EQ(errorOf([&] { sceneFromMeshFile(file, {.maxBodies = 2}); }),
            file.string() +
                ": 3 meshes make as many bodies, above the limit of 2 (--max-bodies raises it)");
}

}  // namespace
}  // namespace softbake
