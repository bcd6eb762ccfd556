// The options of a bake in-process: every run option of the option table lands in a field of
// RunOptions, and the run's record gives back exactly the options it was made with.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "bake/run_options.hpp"
#include "bake/run_record.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/option_table.hpp"
#include "importers/scene_file.hpp"

namespace softbake {
namespace {

using Json = nlohmann::json;

// The run's own fields, as text to compare.
std::string fieldsOf(const RunOptions& o) {
  return cat("while ", o.renderWhileSimulating, " voxel ", o.voxelSize.value_or(-1), " fog ",
             o.vdbFog, " up ", o.upAxis.value_or("-"), " compression ",
             o.vdbCompression.value_or("-"), " threads ", o.threads, " quiet ", o.quiet, " gib ",
             o.maxOutputGib, " cache ", o.cache, " only ", o.cacheOnly, " every ",
             o.checkpointEvery.value_or(-1), " resume ", o.resume, " report ",
             o.report.value_or("-").string(), " lossy ", o.load.acceptLossyImport, " vertices ",
             o.load.maxVertices.value_or(0), " faces ", o.load.maxFaces.value_or(0), " memory ",
             o.load.maxImportMemoryMib.value_or(0), " seconds ",
             o.load.maxImportSeconds.value_or(0), " bodies ", o.load.maxBodies);
}

// A value the option takes that no default has.
Json valueFor(const OptionSpec& spec) {
  switch (spec.kind) {
    case OptionKind::Flag:
      return true;
    case OptionKind::Whole:
    case OptionKind::Substeps:
      return (long long)spec.low + 2;
    case OptionKind::Number:
      return spec.low + 0.5;
    case OptionKind::Choice:
      return spec.choices().back();
    case OptionKind::ImageSize:
      return Json::array({(long long)spec.low, (long long)spec.low + 1});
    case OptionKind::Path:
      return "report_folder";
  }
  return nullptr;
}

TEST(RunOptions, EveryRunOptionOfTheTableLandsInAFieldOfItsOwn) {
  const std::string defaults = fieldsOf(RunOptions());
  int landed = 0;
  for (const OptionSpec& spec : optionTable()) {
    if (!spec.sceneKey.empty()) continue;  // the scene's: OptionTable's tests
    RunOptions options;
    giveOption(options.given, spec, valueFor(spec));
    ASSERT_NO_THROW(landRunOptions(options)) << spec.name;
    EXPECT_NE(fieldsOf(options), defaults) << spec.flag() << " landed nowhere";
    ++landed;
  }
  EXPECT_GE(landed, 18);
}

TEST(RunOptions, OptionsThatExcludeEachOtherAreRefused) {
  RunOptions options;
  giveOption(options.given, optionSpec("no-cache"), true);
  giveOption(options.given, optionSpec("cache-only"), true);
  try {
    landRunOptions(options);
    ADD_FAILURE() << "--cache-only with --no-cache was taken";
  } catch (const Error& error) {
    EXPECT_STREQ(error.what(), "--cache-only excludes --no-cache");
  }
}

TEST(RunOptions, TheRecordGivesBackTheOptionsItWasMadeWith) {
  RunOptions run;
  run.input = "default";
  for (const OptionSpec& spec : optionTable())
    if (spec.recorded && spec.name != "no-render" && spec.name != "no-response")
      giveOption(run.given, spec, valueFor(spec));
  landRunOptions(run);
  const SceneFile scene = defaultScene();
  const nlohmann::ordered_json record = runRecord(run, scene, 7);
  // --checkpoint-every is recorded as the interval the run chose, given or not.
  for (const OptionSpec& spec : optionTable())
    if (spec.name != "checkpoint-every") {
      EXPECT_EQ(record["options"].contains(std::string(spec.name)), spec.recorded) << spec.name;
    }
  const RunOptions back = runOptionsFromRecord(record, "out", "manifest.json");
  Json expected = run.given;
  expected["checkpoint-every"] = 7;
  EXPECT_EQ(back.given, expected);
  EXPECT_EQ(fieldsOf(back), fieldsOf(run).replace(fieldsOf(run).find("every -1"), 8, "every 7"));
  EXPECT_TRUE(runRecordDifferences(record, runRecord(back, scene, 7)).empty());
}

}  // namespace
}  // namespace softbake
