// The simulation cache through the real binary, as a farm or an impatient user meets it: a run
// killed at the worst moments, stopped by SIGTERM or by a full disk, then `--resume`d, writes the
// same bytes as a run that was never stopped; `export` writes a run's frames again from its cache
// alone; a changed input or a damaged cache file is refused by name.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <random>
#include <thread>

#include <nlohmann/json.hpp>

#include "tests/cli/softbake_process.hpp"

extern char** environ;

namespace softbake::test {
namespace {

namespace fs = std::filesystem;
using Files = std::map<std::string, std::string>;  // relative path -> bytes

/// Every file under `folder`, hidden temporary files included: a torn or stray file is a
/// difference too.
Files readTree(const fs::path& folder) {
  Files files;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder))
    if (entry.is_regular_file())
      files[fs::relative(entry.path(), folder).string()] = readFile(entry.path());
  return files;
}

/// Names the files that differ, so a failure says where.
void expectSameFiles(const Files& expected, const Files& actual) {
  std::vector<std::string> differences;
  for (const auto& [name, bytes] : expected) {
    const auto match = actual.find(name);
    if (match == actual.end())
      differences.push_back("missing " + name);
    else if (match->second != bytes)
      differences.push_back("differs " + name);
  }
  for (const auto& [name, bytes] : actual)
    if (!expected.count(name)) differences.push_back("extra " + name);
  EXPECT_TRUE(differences.empty())
      << differences.size() << " differences, the first: " << differences.front();
}

nlohmann::json readManifestJson(const fs::path& out) {
  return nlohmann::json::parse(readFile(out / "manifest.json"));
}

/// `softbake ARGUMENTS` started in the background, its output to `log`; `environment` entries
/// ("NAME=value") are added to this process's.
pid_t startSoftbake(const std::vector<std::string>& arguments, const fs::path& log,
                    const std::vector<std::string>& environment = {}) {
  std::vector<std::string> words{SOFTBAKE_BINARY};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  std::vector<std::string> variables(environment);
  for (char** e = environ; *e; ++e) variables.push_back(*e);
  std::vector<char*> envp;
  for (std::string& variable : variables) envp.push_back(variable.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  const int failed = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (failed != 0) ADD_FAILURE() << "cannot start " << argv[0];
  return failed == 0 ? pid : -1;
}

/// The wait status of `pid`.
int waitFor(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

/// How waitForFile() ended.
struct Waited {
  bool appeared = false;  ///< the file is there, seen while the process ran
  bool hung = false;      ///< the deadline passed; the process was killed
  int endStatus = 0;      ///< otherwise the process ended first: its wait status
};

/// Waits until `file` exists while `pid` runs. A run that ends first, or one still short of the
/// file at a deadline far beyond any run of the test's scene (then killed), ends the wait as a
/// failure for the caller to report, instead of a test that hangs or signals a process that
/// already finished. The deadline bounds the wait only; no result depends on it. Polls: the file
/// appears by a rename in another process.
Waited waitForFile(pid_t pid, const fs::path& file) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  Waited waited;
  while (!fs::exists(file)) {
    if (waitpid(pid, &waited.endStatus, WNOHANG) == pid) return waited;
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitFor(pid);
      waited.hung = true;
      return waited;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  waited.appeared = true;
  return waited;
}

/// Why a wait did not see `file` appear, with the run's `log`.
std::string missed(const Waited& waited, const fs::path& file, const fs::path& log) {
  std::string why = "no " + file.string();
  if (waited.hung)
    why += " after 2 minutes: the run hangs";
  else if (WIFEXITED(waited.endStatus))
    why += ": the run ended first, exit code " + std::to_string(WEXITSTATUS(waited.endStatus));
  else
    why += ": the run was killed first, by signal " + std::to_string(WTERMSIG(waited.endStatus));
  return why + "\n" + readFile(log);
}

/// The seed of the random kills: SOFTBAKE_TEST_SEED, to repeat a failure, else a new one.
std::optional<unsigned> killSeed() {
  const char* text = std::getenv("SOFTBAKE_TEST_SEED");
  if (!text) return std::random_device()();
  char* end = nullptr;
  errno = 0;
  const unsigned long long value = std::strtoull(text, &end, 10);
  if (*text < '0' || *text > '9' || *end != '\0' || errno != 0 || value > UINT_MAX)
    return std::nullopt;
  return unsigned(value);
}

/// A scene of the paper's figure 4 (two bodies meeting over the ground), short, with its contacts.
constexpr const char* kTwoBodies = R"({
  "name": "two_bodies",
  "settings": { "fps": 24, "frames": 36 },
  "bodies": [
    { "name": "lower", "mesh": { "primitive": "icosphere", "subdivisions": 3, "radius": 0.6 },
      "transform": { "translate": [0, 0.65, 0] }, "material": "rubber" },
    { "name": "upper", "mesh": { "primitive": "icosphere", "subdivisions": 3, "radius": 0.5 },
      "transform": { "translate": [0.03, 1.9, 0.0] }, "material": "jelly", "mass": 0.5,
      "velocity": [0, -2, 0] }
  ],
  "colliders": [ { "type": "plane", "name": "ground" } ],
  "output": { "contacts": true }
})";

class Resume : public CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    scene_ = writeScene("two_bodies.json", kTwoBodies);
  }

  /// `run` of the scene into `out` with every output the cache feeds, small PNGs.
  std::string runArguments(const fs::path& out, const std::string& extra = "") const {
    return "run " + quoted(scene_) + " -o " + quoted(out) +
           " --vdb --render --size 160x90 --checkpoint-every 4 -q " + extra;
  }
  std::vector<std::string> runWords(const fs::path& out) const {
    return {"run",    scene_.string(),      "-o", out.string(), "--vdb", "--render", "--size",
            "160x90", "--checkpoint-every", "4",  "-q"};
  }

  /// The files of an uninterrupted run.
  const Files& reference() {
    if (reference_.empty()) {
      const fs::path out = folder_ / "reference";
      const Result result = runSoftbake(runArguments(out));
      EXPECT_EQ(result.exitCode, 0) << result.output;
      reference_ = readTree(out);
      EXPECT_GT(reference_.size(), 36u * 5);
    }
    return reference_;
  }

  void expectResumesToReference(const fs::path& out) {
    const Result resumed = runSoftbake(runArguments(out, "--resume"));
    ASSERT_EQ(resumed.exitCode, 0) << resumed.output;
    expectSameFiles(reference(), readTree(out));
  }

  fs::path scene_;
  Files reference_;
};

TEST_F(Resume, KilledAtTheWorstMomentsThenResumedIsByteIdentical) {
  // Killed after each file's data is written and before its rename: early, during a checkpoint,
  // in each writer, on the last frame.
  for (const std::string file :
       {"two_bodies_0002.sbframe", "two_bodies_0009.sbcheckpoint", "two_bodies_0014.obj",
        "two_bodies_0021.png", "two_bodies_0027.json", "two_bodies_0036.sbframe"}) {
    SCOPED_TRACE(file);
    const fs::path out = folder_ / ("killed_" + file);
    const pid_t pid = startSoftbake(runWords(out), folder_ / "log.txt",
                                    {"SOFTBAKE_TEST_KILL_BEFORE_RENAME=" + file});
    const int status = waitFor(pid);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
        << readFile(folder_ / "log.txt");
    EXPECT_EQ(readManifestJson(out)["status"], "incomplete");
    expectResumesToReference(out);
  }
}

TEST_F(Resume, KilledAtRandomFramesThenResumedIsByteIdentical) {
  const std::optional<unsigned> seed = killSeed();
  ASSERT_TRUE(seed) << "SOFTBAKE_TEST_SEED=" << std::getenv("SOFTBAKE_TEST_SEED")
                    << " is not a seed: a whole number below 2^32";
  RecordProperty("seed", std::to_string(*seed));
  std::printf("seed %u (SOFTBAKE_TEST_SEED=%u repeats this test's kills)\n", *seed, *seed);
  SCOPED_TRACE("seed " + std::to_string(*seed) + " (SOFTBAKE_TEST_SEED repeats it)");
  std::mt19937 random(*seed);
  for (int trial = 0; trial < 3; ++trial) {
    // A kill -9 from outside once the cache holds a random number of frames.
    const int frames = std::uniform_int_distribution<int>(2, 34)(random);
    SCOPED_TRACE("trial " + std::to_string(trial) + ", killed at cache frame " +
                 std::to_string(frames));
    const fs::path out = folder_ / ("random_" + std::to_string(trial));
    char name[64];
    std::snprintf(name, sizeof name, "cache/two_bodies_%04d.sbframe", frames);
    const fs::path log = folder_ / "log.txt";
    const pid_t pid = startSoftbake(runWords(out), log);
    ASSERT_GT(pid, 0);
    const Waited waited = waitForFile(pid, out / name);
    ASSERT_TRUE(waited.appeared) << missed(waited, out / name, log);
    kill(pid, SIGKILL);
    // The kill landed mid-run: it had started (frame `frames` is in the cache), the process was
    // still there to be killed (a finished one would have exited), and the run had not finished
    // (the manifest is not complete).
    const int status = waitFor(pid);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
        << "the run ended before the kill\n"
        << readFile(log);
    ASSERT_EQ(readManifestJson(out)["status"], "incomplete");
    expectResumesToReference(out);
  }
}

TEST_F(Resume, SigtermLeavesAnIncompleteManifestAndTheResumeCommand) {
  const fs::path out = folder_ / "terminated";
  const pid_t pid = startSoftbake(runWords(out), folder_ / "log.txt");
  ASSERT_GT(pid, 0);
  const fs::path fifth = out / "cache/two_bodies_0005.sbframe";
  const Waited waited = waitForFile(pid, fifth);
  ASSERT_TRUE(waited.appeared) << missed(waited, fifth, folder_ / "log.txt");
  kill(pid, SIGTERM);
  const int status = waitFor(pid);
  const std::string log = readFile(folder_ / "log.txt");
  ASSERT_TRUE(WIFEXITED(status)) << log;
  EXPECT_EQ(WEXITSTATUS(status), 143) << log;  // 128 + SIGTERM, as docs/commands.md says
  EXPECT_NE(log.find("interrupted by SIGTERM"), std::string::npos) << log;
  EXPECT_NE(log.find("--resume"), std::string::npos) << log;
  const nlohmann::json manifest = readManifestJson(out);
  EXPECT_EQ(manifest["status"], "incomplete");
  EXPECT_NE(manifest["reason"].get<std::string>().find("SIGTERM"), std::string::npos);
  // PNG frames are rendered from the cache after the simulation, so none is complete yet.
  EXPECT_EQ(manifest["frames_complete"], 0);
  EXPECT_TRUE(fs::exists(out / "cache/two_bodies_0005.sbframe"));
  EXPECT_FALSE(fs::exists(out / "cache/two_bodies_0036.sbframe"));
  expectResumesToReference(out);
}

TEST_F(Resume, AFullDiskNamesTheFileLeavesNoTornFileAndResumes) {
  // Contacts and the cache only: a file-size limit under the largest file stops the run in the
  // middle, as a disk filling up would. Which file meets the limit first (a contact file that
  // grew with the contacts, or a checkpoint that holds the touching pairs) is the scene's; the run
  // must name that one.
  std::string text = kTwoBodies;
  const std::string output = R"("output": { "contacts": true })";
  text.replace(text.find(output), output.size(), R"("output": { "obj": false, "contacts": true })");
  const fs::path scene = writeScene("contacts_only.json", text);
  const auto arguments = [&](const fs::path& out) {
    return "run " + quoted(scene) + " -o " + quoted(out) + " --checkpoint-every 4 -q";
  };
  const fs::path referenceOut = folder_ / "contacts_reference";
  ASSERT_EQ(runSoftbake(arguments(referenceOut)).exitCode, 0);
  const Files reference = readTree(referenceOut);
  std::size_t largest = 0, first = 0;
  for (const auto& [name, bytes] : reference) {
    largest = std::max(largest, bytes.size());
    if (name == "contacts/two_bodies_0001.json") first = bytes.size();
  }
  const std::size_t limitBlocks = (largest - 1) / 1024;  // ulimit -f counts 1024-byte blocks
  ASSERT_GT(limitBlocks * 1024, first) << "the scene no longer fits the test";

  const fs::path out = folder_ / "full";
  const std::string command = "sh -c " +
                              quoted("ulimit -f " + std::to_string(limitBlocks) + "; exec " +
                                     SOFTBAKE_BINARY + " " + arguments(out)) +
                              " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string log;
  char buffer[4096];
  for (std::size_t read; (read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;)
    log.append(buffer, read);
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status)) << log;
  EXPECT_EQ(WEXITSTATUS(status), 3) << log;  // an output could not be written
  EXPECT_NE(log.find("File too large"), std::string::npos) << log;
  // The file named: "cannot write '<out>/<folder>/two_bodies_NNNN.<ext>'".
  const std::string named = "cannot write '" + out.string() + "/";
  const std::size_t at = log.find(named);
  ASSERT_NE(at, std::string::npos) << log;
  const std::string file =
      log.substr(at + named.size(), log.find('\'', at + named.size()) - at - named.size());
  EXPECT_TRUE(file.rfind("contacts/two_bodies_00", 0) == 0 ||
              file.rfind("cache/two_bodies_00", 0) == 0)
      << file;
  const nlohmann::json manifest = readManifestJson(out);
  EXPECT_EQ(manifest["status"], "failed");
  EXPECT_NE(manifest["reason"].get<std::string>().find(file), std::string::npos) << file;
  EXPECT_GT(manifest["frames_complete"].get<int>(), 1);
  for (const auto& [name, bytes] : readTree(out)) {
    EXPECT_EQ(fs::path(name).filename().string().find(".tmp-"), std::string::npos) << name;
    if (name.rfind("contacts/", 0) == 0) {  // every contact file there is whole
      EXPECT_TRUE(nlohmann::json::accept(bytes)) << name;
    }
  }
  // Space freed: no limit now.
  const Result resumed = runSoftbake(arguments(out) + " --resume");
  ASSERT_EQ(resumed.exitCode, 0) << resumed.output;
  expectSameFiles(reference, readTree(out));
}

TEST_F(Resume, PassesOverADamagedCheckpoint) {
  const fs::path out = folder_ / "damaged";
  const pid_t pid = startSoftbake(runWords(out), folder_ / "log.txt",
                                  {"SOFTBAKE_TEST_KILL_BEFORE_RENAME=two_bodies_0030.sbframe"});
  waitFor(pid);
  // The checkpoint a resume would start from: the latest before the first frame with a file the
  // simulation writes missing (the writers run at their own pace, so that is not always frame 30;
  // PNG frames come from the cache afterwards).
  int firstIncomplete = 1;
  for (;; ++firstIncomplete) {
    char number[16];
    std::snprintf(number, sizeof number, "_%04d.", firstIncomplete);
    bool whole = true;
    for (const auto& [name, bytes] : reference())
      if (name.find(number) != std::string::npos && name.rfind("png/", 0) != 0 &&
          !fs::exists(out / name))
        whole = false;
    if (!whole) break;
  }
  const int latest = 1 + (firstIncomplete - 2) / 4 * 4;  // checkpoints at 5, 9, 13, …
  ASSERT_GE(latest, 9) << "the run was killed too early for this test";
  char name[64];
  std::snprintf(name, sizeof name, "cache/two_bodies_%04d.sbcheckpoint", latest);
  const fs::path checkpoint = out / name;
  ASSERT_TRUE(fs::exists(checkpoint));
  std::string bytes = readFile(checkpoint);
  bytes[bytes.size() / 2] ^= 0x01;
  std::ofstream(checkpoint, std::ios::binary) << bytes;

  const Result resumed = runSoftbake(runArguments(out, "--resume"));
  ASSERT_EQ(resumed.exitCode, 0) << resumed.output;
  EXPECT_NE(resumed.output.find(checkpoint.filename().string() +
                                ": the cache file's data does not match its checksum"),
            std::string::npos)
      << resumed.output;
  EXPECT_NE(resumed.output.find("from the checkpoint of frame " + std::to_string(latest - 4)),
            std::string::npos)
      << resumed.output;
  // The damaged checkpoint is a file the resumed run did not write again: put it right to compare.
  std::ofstream(checkpoint, std::ios::binary) << reference().at(name);
  expectSameFiles(reference(), readTree(out));
}

TEST_F(Resume, RefusesAChangedSettingOrInputFile) {
  const fs::path out = folder_ / "changed";
  ASSERT_EQ(runSoftbake(runArguments(out, "--frames 12")).exitCode, 0);
  const Result frames = runSoftbake(runArguments(out, "--frames 13 --resume"));
  EXPECT_EQ(frames.exitCode, 1);
  EXPECT_NE(frames.output.find("--frames: 12 then, 13 now"), std::string::npos) << frames.output;
  std::ofstream(scene_, std::ios::app) << "\n";  // the same scene, other bytes
  const Result file = runSoftbake(runArguments(out, "--frames 12 --resume"));
  EXPECT_EQ(file.exitCode, 1);
  EXPECT_NE(file.output.find("two_bodies.json' changed (SHA-256"), std::string::npos)
      << file.output;
  const Result nothing = runSoftbake(runArguments(folder_ / "never_run", "--resume"));
  EXPECT_EQ(nothing.exitCode, 1);
  EXPECT_NE(nothing.output.find("manifest"), std::string::npos) << nothing.output;
}

TEST_F(Resume, ExportWritesTheRunsFilesFromTheCacheAlone) {
  const fs::path out = folder_ / "exported";
  ASSERT_EQ(runSoftbake(runArguments(out)).exitCode, 0);
  for (const char* folder : {"obj", "png", "vdb", "contacts"}) fs::remove_all(out / folder);
  // Two machines' worth of frames, each its own export.
  for (const char* range : {"1:20", "21:36"}) {
    const Result result = runSoftbake("export " + quoted(out) + " --frames " + range +
                                      " --obj --png --vdb --contacts -q");
    ASSERT_EQ(result.exitCode, 0) << result.output;
  }
  expectSameFiles(reference(), readTree(out));

  // A cache frame with one bit flipped is refused by its checksum, naming the file.
  const fs::path frame = out / "cache/two_bodies_0030.sbframe";
  std::string bytes = readFile(frame);
  bytes[bytes.size() - 7] ^= 0x10;
  std::ofstream(frame, std::ios::binary) << bytes;
  const Result damaged = runSoftbake("export " + quoted(out) + " --frames 30 --obj");
  EXPECT_EQ(damaged.exitCode, 1);
  EXPECT_NE(damaged.output.find("two_bodies_0030.sbframe: the cache file's data does not match "
                                "its checksum"),
            std::string::npos)
      << damaged.output;
}

TEST_F(Resume, ExportNeedsACacheAndFramesItHolds) {
  const fs::path out = folder_ / "uncached";
  ASSERT_EQ(
      runSoftbake("run " + quoted(scene_) + " -o " + quoted(out) + " --frames 4 --no-cache -q")
          .exitCode,
      0);
  const Result uncached = runSoftbake("export " + quoted(out) + " --obj");
  EXPECT_EQ(uncached.exitCode, 1);
  EXPECT_NE(uncached.output.find("--no-cache"), std::string::npos) << uncached.output;
  EXPECT_FALSE(fs::exists(out / "cache"));

  const fs::path cached = folder_ / "cached";
  ASSERT_EQ(
      runSoftbake("run " + quoted(scene_) + " -o " + quoted(cached) + " --frames 4 -q").exitCode,
      0);
  const Result beyond = runSoftbake("export " + quoted(cached) + " --frames 3:5 --obj");
  EXPECT_EQ(beyond.exitCode, 1);
  EXPECT_NE(beyond.output.find("the cache holds frames 1 to 4"), std::string::npos)
      << beyond.output;
  const Result none = runSoftbake("export " + quoted(cached));
  EXPECT_EQ(none.exitCode, 1);
  EXPECT_NE(none.output.find("--obj"), std::string::npos) << none.output;
}

}  // namespace
}  // namespace softbake::test
