// Wedges, the farm's scripts and `verify`, through the binary: variants are the cartesian product
// with a table of what each sets and bake to what a single run of their scene writes; a farm's
// sbatch scripts hold their directives where sbatch reads them; verify finds every kind of hole.
// (The farm on a real Slurm cluster is scripts/test_slurm.sh, run by CI.)
#include <gtest/gtest.h>

#include <map>

#include <nlohmann/json.hpp>

#include "tests/cli/softbake_process.hpp"

namespace softbake::test {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScene = R"({
  "name": "pair",
  "settings": { "fps": 24, "frames": 6 },
  "bodies": [
    { "name": "lower", "mesh": { "primitive": "icosphere", "subdivisions": 2, "radius": 0.6 },
      "transform": { "translate": [0, 0.65, 0] }, "material": "rubber" },
    { "name": "upper", "mesh": { "primitive": "icosphere", "subdivisions": 2, "radius": 0.5 },
      "transform": { "translate": [0.03, 1.9, 0.0] }, "material": "jelly",
      "velocity": [0, -2, 0] }
  ],
  "colliders": [ { "type": "plane", "name": "ground" } ],
  "output": { "contacts": true }
})";

std::map<std::string, std::string> outputs(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder)) {
    const std::string name = fs::relative(entry.path(), folder).string();
    if (entry.is_regular_file() && name != "manifest.json" && name != "scene.json" &&
        name != "run.log")
      files[name] = readFile(entry.path());
  }
  return files;
}

TEST_F(CliTest, AWedgeIsTheCartesianProductWithATable) {
  const fs::path scene = writeScene("pair.json", kScene);
  const fs::path out = folder_ / "wedge";
  const Result result = runSoftbake("wedge " + quoted(scene) +
                                    " --vary 'bodies[1].material=jelly,\"rubber\"' --vary "
                                    "'bodies[1].velocity=[0,-1,0],[0,-3,0]' --no-bake -o " +
                                    quoted(out));
  ASSERT_EQ(result.exitCode, 0) << result.output;
  // The first --vary slowest: wedge_003 is rubber at 3 m/s.
  const nlohmann::json variant = nlohmann::json::parse(readFile(out / "wedge_003/scene.json"));
  EXPECT_EQ(variant["bodies"][1]["material"], "rubber");
  EXPECT_EQ(variant["bodies"][1]["velocity"], nlohmann::json::array({0, -3, 0}));
  EXPECT_EQ(variant["bodies"][0]["material"], "rubber");  // untouched
  EXPECT_EQ(readFile(out / "wedge.csv"),
            "variant,bodies[1].material,bodies[1].velocity\n"
            "wedge_000,jelly,\"[0,-1,0]\"\nwedge_001,jelly,\"[0,-3,0]\"\n"
            "wedge_002,rubber,\"[0,-1,0]\"\nwedge_003,rubber,\"[0,-3,0]\"\n");
  EXPECT_NE(readFile(out / "wedge.md").find("| wedge_003 | rubber | [0,-3,0] |"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(out / "wedge_000/obj"));  // --no-bake
}

TEST_F(CliTest, AWedgeRefusesAPathTheSceneLacksAndABadValueByVariant) {
  const fs::path scene = writeScene("pair.json", kScene);
  const Result path = runSoftbake("wedge " + quoted(scene) + " --vary 'bodies[5].mass=1' -o " +
                                  quoted(folder_ / "a"));
  EXPECT_EQ(path.exitCode, 1);
  EXPECT_NE(path.output.find("--vary bodies[5].mass: the scene has no bodies[5]"),
            std::string::npos)
      << path.output;
  const Result value = runSoftbake("wedge " + quoted(scene) + " --vary 'bodies[1].mass=2,-1' -o " +
                                   quoted(folder_ / "b"));
  EXPECT_EQ(value.exitCode, 1);
  EXPECT_NE(value.output.find("wedge variant wedge_001 (bodies[1].mass=-1)"), std::string::npos)
      << value.output;
  EXPECT_FALSE(fs::exists(folder_ / "b/wedge_000"));
  const Result options = runSoftbake("wedge " + quoted(scene) + " --vary 'settings.fps=24' -o " +
                                     quoted(folder_ / "c") + " -- --no-such-flag");
  EXPECT_EQ(options.exitCode, 1);
  EXPECT_NE(options.output.find("the run options after --"), std::string::npos) << options.output;
}

TEST_F(CliTest, WedgeVariantsBakeToWhatASingleRunWrites) {
  const fs::path scene = writeScene("pair.json", kScene);
  const fs::path out = folder_ / "wedge";
  const Result result =
      runSoftbake("wedge " + quoted(scene) + " --vary 'bodies[1].mass=0.5,2' -o " + quoted(out) +
                  " -- --vdb --voxel-size 0.05");
  ASSERT_EQ(result.exitCode, 0) << result.output;
  for (const char* name : {"wedge_000", "wedge_001"}) {
    const fs::path single = folder_ / (std::string("single_") + name);
    ASSERT_EQ(runSoftbake("run " + quoted(out / name / "scene.json") + " -o " + quoted(single) +
                          " --vdb --voxel-size 0.05 -q")
                  .exitCode,
              0);
    const auto expected = outputs(single);
    EXPECT_GT(expected.size(), 6u * 4);
    EXPECT_TRUE(outputs(out / name) == expected) << name;
  }
  EXPECT_NE(outputs(out / "wedge_000"), outputs(out / "wedge_001"));
}

TEST_F(CliTest, FarmScriptsHoldTheirDirectivesWhereSbatchReadsThem) {
  const fs::path scene = writeScene("pair.json", kScene);
  const fs::path out = folder_ / "farm";
  const Result result =
      runSoftbake("farm slurm " + quoted(scene) + " -o " + quoted(out) +
                  " --vary 'bodies[1].mass=0.5,2' --chunk 4 --partition short -- --frames 10");
  ASSERT_EQ(result.exitCode, 0) << result.output;
  const std::string exporting = readFile(out / "slurm/export_wedge_001.sbatch");
  // sbatch stops reading directives at the first command.
  const std::size_t firstCommand = exporting.find("\nset -euo pipefail");
  ASSERT_NE(firstCommand, std::string::npos) << exporting;
  for (const char* directive : {"#SBATCH --array=0-2\n", "#SBATCH --partition=short\n",
                                "#SBATCH --output=", "#SBATCH --chdir="}) {
    const std::size_t at = exporting.find(directive);
    EXPECT_NE(at, std::string::npos) << directive;
    EXPECT_LT(at, firstCommand) << directive;
  }
  EXPECT_NE(exporting.find("if [ \"$last\" -gt 10 ]; then last=10; fi"), std::string::npos)
      << exporting;
  EXPECT_NE(exporting.find("export " + (out / "wedge_001").string() + " --all --frames"),
            std::string::npos)
      << exporting;
  const std::string simulate = readFile(out / "slurm/simulate_wedge_000.sbatch");
  EXPECT_NE(simulate.find("--cache-only"), std::string::npos) << simulate;
  EXPECT_NE(simulate.find("--frames 10"), std::string::npos) << simulate;
  const std::string submit = readFile(out / "slurm/submit.sh");
  EXPECT_NE(submit.find("--dependency=afterok:$sim_wedge_001 export_wedge_001.sbatch"),
            std::string::npos)
      << submit;
  EXPECT_NE(submit.find("--dependency=afterok:$export_wedge_000:$export_wedge_001 verify.sbatch"),
            std::string::npos)
      << submit;
  const Result tooMany = runSoftbake("farm slurm " + quoted(scene) + " -o " +
                                     quoted(folder_ / "big") + " --chunk 1 -- --frames 2000");
  EXPECT_EQ(tooMany.exitCode, 1);
  EXPECT_NE(tooMany.output.find("MaxArraySize"), std::string::npos) << tooMany.output;
}

TEST_F(CliTest, VerifyFindsEveryKindOfHole) {
  const fs::path scene = writeScene("pair.json", kScene);
  const fs::path out = folder_ / "run";
  ASSERT_EQ(runSoftbake("run " + quoted(scene) + " -o " + quoted(out) + " -q").exitCode, 0);
  const Result whole = runSoftbake("verify " + quoted(out));
  EXPECT_EQ(whole.exitCode, 0) << whole.output;
  EXPECT_NE(whole.output.find("whole: 3 sequences of 6 frames"), std::string::npos) << whole.output;

  fs::remove(out / "obj/pair_0003.obj");
  fs::copy_file(out / "contacts/pair_0002.json", out / "contacts/pair_00002.json");
  std::ofstream(out / "obj/.pair_0004.obj.tmp-1-0") << "v 0 0";
  std::ofstream(out / "obj/pair_0009.obj") << "v 0 0 0\n";
  std::string cached = readFile(out / "cache/pair_0005.sbframe");
  cached[100] ^= 0x20;
  std::ofstream(out / "cache/pair_0005.sbframe", std::ios::binary) << cached;
  const Result holes = runSoftbake("verify " + quoted(out));
  EXPECT_EQ(holes.exitCode, 1);
  for (const char* problem :
       {"5 problems", "obj/pair_0003.obj: missing or unreadable",
        "contacts: frame 2 is there 2 times", "obj/.pair_0004.obj.tmp-1-0: a temporary file",
        "obj: frame 9 (pair_0009.obj) is outside the run's frames 1 to 6",
        "cache/pair_0005.sbframe: the cache file's data does not match its checksum"})
    EXPECT_NE(holes.output.find(problem), std::string::npos) << problem << "\n" << holes.output;
}

}  // namespace
}  // namespace softbake::test
