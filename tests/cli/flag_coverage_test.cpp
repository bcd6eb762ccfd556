// Every flag of every command's --help is documented in the command reference (docs/commands.md)
// and has a test that exercises its effect. The table names that test for each flag; the check
// reads the test's source and wants the flag (or its short form) in it, so a renamed test, a new
// flag without a test, or a flag dropped from --help but left here all fail.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "tests/cli/softbake_process.hpp"

namespace softbake::test {
namespace {

namespace fs = std::filesystem;

struct FlagTest {
  std::string_view command;  ///< as typed after `softbake`; empty for the top level
  std::string_view flag;
  /// "Suite.Name" of a GoogleTest test, or a test script's path from the repository root.
  std::string_view test;
};

// clang-format off
constexpr FlagTest kFlagTests[] = {
    {"run", "--accept-lossy-import", "ImportCliTest.AcceptingTheLossRunsWithAWarningNamingTheFile"},
    {"run", "--max-vertices", "ImportLimits.FacesAndVerticesAboveTheirCapsAreRefusedNamingTheFile"},
    {"run", "--max-faces", "ImportCliTest.AFileAboveTheFaceCapIsRefusedNamingTheFileAndTheFlag"},
    {"run", "--max-import-memory", "ImportLimits.MemoryAboveTheCapIsRefusedNamingTheCap"},
    {"run", "--max-import-seconds", "ImportCliTest.AnImportPastItsTimeLimitExitsWithOneNamingTheLimitAndWritesNothing"},
    {"run", "--max-bodies", "ImportCliTest.TooManyBodiesAreRefusedForBuiltInScenesToo"},
    {"run", "--out", "CliTest.DefaultSceneWritesFramesAndManifestAndSaysWhere"},
    {"run", "--frames", "CliTest.ALongerRunThenAShorterOneLeavesOneConsistentSequence"},
    {"run", "--fps", "RunFlags.FpsSetsTheFramesTimesAndTheSimulatedTime"},
    {"run", "--integrator", "CliTest.TooFewExplicitSubstepsWarnsWithTheBound"},
    {"run", "--substeps", "CliTest.TooFewSubstepsBlowsUpWithAClearErrorAndNoNaNInAnyFile"},
    {"run", "--frame-padding", "RunFlags.FramePaddingSetsTheDigitsOfEveryFileName"},
    {"run", "--broadphase", "CliTest.EveryBroadPhaseWritesTheSameBytesWithAndWithoutThePairCache"},
    {"run", "--levels", "RunFlags.LevelsReachTheSbhashBroadPhaseAndChangeNoResult"},
    {"run", "--response", "RunFlags.ResponseNoneLetsTheBallsPassThroughEachOtherAndPaperDiffers"},
    {"run", "--no-pair-cache", "CliTest.EveryBroadPhaseWritesTheSameBytesWithAndWithoutThePairCache"},
    {"run", "--no-response", "CliTest.NoResponseLetsTheBallFallThroughTheGround"},
    {"run", "--no-self-collision", "RunFlags.NoSelfCollisionLetsAFoldingFlagPassItselfAsTheSceneKeyDoes"},
    {"run", "--contacts", "CliTest.ContactsAreWrittenPerFrameWhenAsked"},
    {"run", "--render", "CliTest.RenderingIsByteIdenticalForOneAndTwoThreads"},
    {"run", "--no-render", "CliTest.NoRenderWritesNoFrames"},
    {"run", "--size", "CliTest.RenderingIsByteIdenticalForOneAndTwoThreads"},
    {"run", "--no-contact-spheres", "RunFlags.NoContactSpheresRemovesTheSpheresAndNothingElse"},
    {"run", "--contacts-view", "RunFlags.ContactsViewChoosesHowTheBodiesAreDrawnInRunSceneAndExport"},
    {"run", "--render-while-simulating", "FlagEffects.RenderWhileSimulatingFramesTheFirstFrameNotTheWholeShot"},
    {"run", "--vdb", "CliTest.VdbFramesAreWrittenAndListedInTheManifest"},
    {"run", "--pc2", "PointCaches.EveryFrameEqualsTheObjSequenceInTheRestMeshsOrder"},
    {"run", "--mdd", "PointCaches.EveryFrameEqualsTheObjSequenceInTheRestMeshsOrder"},
    {"run", "--voxel-size", "CliTest.AVoxelSizeThatWouldNotFitInMemoryIsRefusedBeforeAnyWork"},
    {"run", "--vdb-fog", "RunFlags.VdbFogAddsADensityGridPerBody"},
    {"run", "--vdb-compression", "RunFlags.VdbCompressionShrinksTheFilesAndKeepsEveryVoxel"},
    {"run", "--up", "CliTest.VdbFramesAreWrittenAndListedInTheManifest"},
    {"run", "--threads", "CliTest.OutputIsByteIdenticalForOneAndTwoThreads"},
    {"run", "--quiet", "RunFlags.WithoutQuietALogGetsAProgressLineEveryTenthOfTheRun"},
    {"run", "--max-output-gib", "ImportCliTest.ARunWhoseFramesWouldNotFitTheOutputBoundIsRefusedBeforeAnyWork"},
    {"run", "--no-cache", "PointCaches.LiveAndFromTheCacheAndExportedAreTheSameBytes"},
    {"run", "--checkpoint-every", "Resume.AFullDiskNamesTheFileLeavesNoTornFileAndResumes"},
    {"run", "--cache-only", "CliTest.FarmScriptsHoldTheirDirectivesWhereSbatchReadsThem"},
    {"run", "--resume", "Resume.AFullDiskNamesTheFileLeavesNoTornFileAndResumes"},
    {"run", "--report", "BakeReport.ARunRecordsEveryFrameWithTheVolumesAndEnergyItsObjAndCacheFramesGive"},
    {"compare", "--metric", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--fail", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--fail-percent", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--fail-mean", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--warn", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--warn-percent", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--warn-mean", "CompareCommand.EachMetricHasItsFailAndWarnThresholds"},
    {"compare", "--align", "RenderedCompare.ABodyMovedByOnePercentOfItsSizeFailsAndMultisamplingAndAPixelsCameraShiftPass"},
    {"compare", "--tolerance", "CompareCommand.ExitCodesFollowTheContract"},
    {"compare", "--max-fraction", "CompareCommand.ExitCodesFollowTheContract"},
    {"compare", "--diff", "CompareCommand.ExitCodesFollowTheContract"},
    {"compare", "--report", "CompareReport.TheReportOpensOfflineInChromiumWithARowPerFrameFailuresFirst"},
    {"compare", "--junit", "CompareReport.JunitHoldsACasePerFrameAndAFailurePerFrameThatDiffers"},
    {"compare", "--update", "CompareCommand.UpdateAcceptsTheNewFramesAndThenComparePasses"},
    {"compare", "--max-distance", "BakeCompare.AMaterialChangeFailsNamingTheBodyAndTheFrameWhereItFirstExceeds"},
    {"compare", "--max-rms", "BakeCompare.AMaterialChangeFailsNamingTheBodyAndTheFrameWhereItFirstExceeds"},
    {"compare", "--max-volume-change", "BakeCompare.AMaterialChangeFailsNamingTheBodyAndTheFrameWhereItFirstExceeds"},
    {"compare", "--max-contact-change", "BakeCompare.AMaterialChangeFailsNamingTheBodyAndTheFrameWhereItFirstExceeds"},
    {"bench", "--accept-lossy-import", "ImportCliTest.BenchRefusesTheLossTooUnlessAccepted"},
    {"bench", "--max-vertices", "ImportLimits.FacesAndVerticesAboveTheirCapsAreRefusedNamingTheFile"},
    {"bench", "--max-faces", "ImportCliTest.AFileAboveTheFaceCapIsRefusedNamingTheFileAndTheFlag"},
    {"bench", "--max-import-memory", "ImportLimits.MemoryAboveTheCapIsRefusedNamingTheCap"},
    {"bench", "--max-import-seconds", "ImportCliTest.AnImportPastItsTimeLimitExitsWithOneNamingTheLimitAndWritesNothing"},
    {"bench", "--max-bodies", "ImportCliTest.TooManyBodiesAreRefusedForBuiltInScenesToo"},
    {"bench", "--frames", "BenchFigures.TheSummaryLineAndTheCsvAgree"},
    {"bench", "--steps", "SceneCommandTest.BuiltInSceneJsonParsesAndRunsBackAsAFile"},
    {"bench", "--integrator", "CliTest.TooFewExplicitSubstepsWarnsWithTheBound"},
    {"bench", "--substeps", "BenchFigures.TheSummaryLineAndTheCsvAgree"},
    {"bench", "--broadphase", "BenchFigures.TheSummaryLineAndTheCsvAgree"},
    {"bench", "--levels", "ExitStatus.EveryKindOfBadInputIsOne"},
    {"bench", "--warmup", "BenchFigures.WarmupStepsRunFirstAndAreNotMeasured"},
    {"bench", "--no-self-collision", "RunFlags.NoSelfCollisionLetsAFoldingFlagPassItselfAsTheSceneKeyDoes"},
    {"bench", "--no-pair-cache", "CliTest.EveryBroadPhaseWritesTheSameBytesWithAndWithoutThePairCache"},
    {"bench", "--threads", "FlagEffects.BenchWithExportsTimesEveryWriterAndKeepsItsFilesInOut"},
    {"bench", "--csv", "BenchFigures.TheSummaryLineAndTheCsvAgree"},
    {"bench", "--with-exports", "FlagEffects.BenchWithExportsTimesEveryWriterAndKeepsItsFilesInOut"},
    {"bench", "--out", "FlagEffects.BenchWithExportsTimesEveryWriterAndKeepsItsFilesInOut"},
    {"export", "--frames", "PointCaches.LiveAndFromTheCacheAndExportedAreTheSameBytes"},
    {"export", "--obj", "FlagEffects.ExportWritesTheSameBytesOnOneThreadAndTwoAndQuietLeavesTheSummary"},
    {"export", "--vdb", "FlagEffects.ExportWritesTheSameBytesOnOneThreadAndTwoAndQuietLeavesTheSummary"},
    {"export", "--png", "Resume.ExportWritesTheRunsFilesFromTheCacheAlone"},
    {"export", "--contacts", "Resume.ExportWritesTheRunsFilesFromTheCacheAlone"},
    {"export", "--pc2", "PointCaches.LiveAndFromTheCacheAndExportedAreTheSameBytes"},
    {"export", "--mdd", "PointCaches.LiveAndFromTheCacheAndExportedAreTheSameBytes"},
    {"export", "--contacts-view", "RunFlags.ContactsViewChoosesHowTheBodiesAreDrawnInRunSceneAndExport"},
    {"export", "--all", "CliTest.FarmScriptsHoldTheirDirectivesWhereSbatchReadsThem"},
    {"export", "--threads", "FlagEffects.ExportWritesTheSameBytesOnOneThreadAndTwoAndQuietLeavesTheSummary"},
    {"export", "--quiet", "FlagEffects.ExportWritesTheSameBytesOnOneThreadAndTwoAndQuietLeavesTheSummary"},
    {"wedge", "--vary", "FlagEffects.WedgeBakesTheSameVariantsOneAtATimeAsTwoAtOnce"},
    {"wedge", "--out", "FlagEffects.WedgeBakesTheSameVariantsOneAtATimeAsTwoAtOnce"},
    {"wedge", "--parallel", "FlagEffects.WedgeBakesTheSameVariantsOneAtATimeAsTwoAtOnce"},
    {"wedge", "--no-bake", "CliTest.AWedgeIsTheCartesianProductWithATable"},
    {"farm slurm", "--out", "FlagEffects.FarmCpusPerTaskReachesSbatchAndTheThreadsOfEveryJob"},
    {"farm slurm", "--vary", "CliTest.FarmScriptsHoldTheirDirectivesWhereSbatchReadsThem"},
    {"farm slurm", "--chunk", "CliTest.FarmScriptsHoldTheirDirectivesWhereSbatchReadsThem"},
    {"farm slurm", "--partition", "CliTest.FarmScriptsHoldTheirDirectivesWhereSbatchReadsThem"},
    {"farm slurm", "--cpus-per-task", "FlagEffects.FarmCpusPerTaskReachesSbatchAndTheThreadsOfEveryJob"},
    {"farm slurm", "--submit", "scripts/test_slurm.sh"},
    {"", "--version", "Version.PrintsTheVersion"},
};
// clang-format on

constexpr std::string_view kCommands[] = {"",      "run",        "compare", "bench", "export",
                                          "wedge", "farm slurm", "verify",  "scene"};

struct HelpFlag {
  std::string flag;
  std::string shortForm;  ///< "-o" for "-o,--out"; empty when there is none
};

/// The options a command's --help lists (its "Options:" section), but --help itself.
std::vector<HelpFlag> helpFlags(std::string_view command) {
  const Result help = runSoftbake(std::string(command) + " --help", false);
  EXPECT_EQ(help.exitCode, 0) << command;
  std::vector<HelpFlag> flags;
  const std::size_t section = help.output.find("\nOptions:\n");
  if (section == std::string::npos) return flags;
  const std::size_t end = help.output.find("\n\n", section + 1);
  const std::string options = help.output.substr(section, end - section);
  static const std::regex line(R"(\n\s+(?:(-\w),)?(--[a-z][a-z0-9-]*))");
  for (std::sregex_iterator it(options.begin(), options.end(), line), last; it != last; ++it)
    if ((*it)[2] != "--help") flags.push_back({(*it)[2], (*it)[1]});
  return flags;
}

/// Every GoogleTest test's source under tests/, by "Suite.Name": from its TEST line to the brace
/// that closes it (clang-format puts that at the start of a line).
std::map<std::string, std::string> testSources() {
  std::map<std::string, std::string> sources;
  static const std::regex header(R"((?:^|\n)TEST(?:_F|_P)?\((\w+),\s*(\w+)\))");
  for (const fs::directory_entry& entry :
       fs::recursive_directory_iterator(fs::path(SOFTBAKE_SOURCE_DIR) / "tests")) {
    if (entry.path().extension() != ".cpp") continue;
    const std::string text = readFile(entry.path());
    for (std::sregex_iterator it(text.begin(), text.end(), header), last; it != last; ++it) {
      const std::size_t start = std::size_t(it->position(0));
      const std::size_t close = text.find("\n}\n", start);
      sources[(*it)[1].str() + "." + (*it)[2].str()] =
          text.substr(start, close == std::string::npos ? std::string::npos : close - start);
    }
  }
  return sources;
}

/// Whether `source` has `flag` or its short form as a word of its own.
bool mentions(const std::string& source, const HelpFlag& flag) {
  const auto word = [&](const std::string& spelling) {
    const std::regex use("(^|[^a-z0-9-])" + spelling + "(?=[^a-z0-9-]|$)");
    return std::regex_search(source, use);
  };
  return word(flag.flag) || (!flag.shortForm.empty() && word(flag.shortForm));
}

TEST(FlagCoverage, EveryFlagInHelpIsDocumentedAndNamesATestThatPassesIt) {
  const fs::path reference = fs::path(SOFTBAKE_SOURCE_DIR) / "docs" / "commands.md";
  ASSERT_TRUE(fs::exists(reference)) << reference;
  const std::string documented = readFile(reference);
  const std::map<std::string, std::string> tests = testSources();
  ASSERT_GT(tests.size(), 300u) << "the test sources were not found";
  std::set<std::pair<std::string, std::string>> listed;
  for (const FlagTest& entry : kFlagTests) listed.emplace(entry.command, entry.flag);

  std::set<std::pair<std::string, std::string>> inHelp;
  for (std::string_view command : kCommands) {
    for (const HelpFlag& flag : helpFlags(command)) {
      const std::string where =
          (command.empty() ? "softbake" : std::string(command)) + " " + flag.flag;
      inHelp.emplace(command, flag.flag);
      EXPECT_TRUE(mentions(documented, {flag.flag, ""})) << where << " is not in " << reference;
      const auto entry = std::find_if(
          std::begin(kFlagTests), std::end(kFlagTests),
          [&](const FlagTest& e) { return e.command == command && e.flag == flag.flag; });
      if (entry == std::end(kFlagTests)) {
        ADD_FAILURE() << where << " has no entry in kFlagTests: name the test of its effect";
        continue;
      }
      const std::string test(entry->test);
      std::string source;
      if (test.find('/') != std::string::npos) {
        const fs::path script = fs::path(SOFTBAKE_SOURCE_DIR) / test;
        ASSERT_TRUE(fs::exists(script)) << script;
        source = readFile(script);
      } else if (const auto found = tests.find(test); found != tests.end()) {
        source = found->second;
      } else {
        ADD_FAILURE() << where << ": no test " << test;
        continue;
      }
      EXPECT_TRUE(mentions(source, flag)) << where << ": " << test << " does not pass it";
    }
  }
  for (const auto& [command, flag] : listed)
    EXPECT_TRUE(inHelp.count({command, flag}))
        << command << " " << flag << " is in kFlagTests but not in --help";
}

}  // namespace
}  // namespace softbake::test
