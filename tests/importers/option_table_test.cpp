// The option table: every scene key it names is checked as its option checks it, and an option
// given on a command line or as a keyword lands where the same key in a scene file lands.

#include <gtest/gtest.h>

#include <set>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/option_table.hpp"
#include "importers/scene_file.hpp"

namespace softbake {
namespace {

using Json = nlohmann::json;

// The options that stand for a whole scene key, not for one value of it (--no-response).
bool ownsItsKey(const OptionSpec& spec) {
  return !spec.sceneKey.empty() && (spec.kind != OptionKind::Flag || spec.value.is_boolean());
}

// A value the option takes, away from the defaults where it can be.
Json goodValue(const OptionSpec& spec) {
  switch (spec.kind) {
    case OptionKind::Flag:
      return !spec.value.get<bool>();  // a flag lands its value; the key takes either
    case OptionKind::Whole:
    case OptionKind::Substeps:
      return (long long)spec.high;
    case OptionKind::Number:
      return spec.high;
    case OptionKind::Choice:
      return spec.choices().back();
    case OptionKind::ImageSize:
      return Json::array({(long long)spec.low, (long long)spec.high});
    case OptionKind::Path:
      return "folder";
  }
  return nullptr;
}

// A value just outside what the option takes.
Json badValue(const OptionSpec& spec) {
  switch (spec.kind) {
    case OptionKind::Flag:
      return "yes";
    case OptionKind::Whole:
    case OptionKind::Substeps:
      return (long long)spec.high + 1;
    case OptionKind::Number:
      return spec.aboveLow ? spec.low : spec.low - 1;
    case OptionKind::Choice:
      return "nonsense";
    case OptionKind::ImageSize:
      return Json::array({(long long)spec.low - 1, (long long)spec.low});
    case OptionKind::Path:
      return "";
  }
  return nullptr;
}

// A scene of one ball with `value` at the option's key.
Json sceneWith(const OptionSpec& spec, const Json& value) {
  Json scene =
      Json::parse(R"({"bodies": [{"mesh": {"primitive": "icosphere", "subdivisions": 1}}]})");
  scene[sceneKeyPointer(spec)] = value;
  return scene;
}

// What of a scene the table's keys set, as text to compare.
std::string settingsOf(const SceneFile& scene) {
  const SimulationSettings& s = scene.setup.settings;
  const CollisionSettings& c = s.collisions;
  const RenderSettings& r = scene.render;
  const OutputOptions& o = scene.output;
  return cat("fps ", s.fps, " frames ", s.frames, " integrator ", integratorName(s.integrator),
             " substeps ", s.substeps, " broadphase ", broadPhaseName(c.broadPhase), " levels ",
             c.subdivisionLevels, " response ", responseModeName(c.response), " pair cache ",
             c.pairCache, " self ", c.selfCollision, " failsafe ", c.failsafe, " in step ",
             c.contactsInStep, " padding ", o.framePadding, " obj ", o.obj, " contacts ",
             o.contacts, " png ", o.png, " vdb ", o.vdb, " pc2 ", o.pc2, " mdd ", o.mdd, " size ",
             r.width.value_or(0), "x", r.height.value_or(0), " spheres ",
             r.contactSpheres ? int(*r.contactSpheres) : -1, " view ",
             r.contactsView.value_or("-"));
}

TEST(OptionTable, NamesAreUniqueAndExclusionsNameOptions) {
  std::set<std::string_view> names;
  for (const OptionSpec& spec : optionTable()) {
    EXPECT_TRUE(names.insert(spec.name).second) << spec.name;
    EXPECT_FALSE(spec.help.empty()) << spec.name;
    if (!spec.excludes.empty()) {
      EXPECT_NO_THROW(optionSpec(spec.excludes)) << spec.name;
    }
  }
}

TEST(OptionTable, EverySceneKeyIsCheckedAsItsOptionChecksIt) {
  int checked = 0;
  for (const OptionSpec& spec : optionTable()) {
    if (!ownsItsKey(spec)) continue;
    ++checked;
    const Json bad = badValue(spec);
    const std::optional<OptionValueError> expected = checkOptionValue(spec, bad, '"');
    ASSERT_TRUE(expected) << spec.name << " takes " << bad;
    try {
      parseScene(sceneWith(spec, bad), "scene.json", {});
      ADD_FAILURE() << spec.sceneKey << ": " << bad << " was taken";
    } catch (const Error& error) {
      EXPECT_EQ(error.what(), cat("scene.json: ", spec.sceneKey, ": ", expected->message));
    }
    EXPECT_NO_THROW(parseScene(sceneWith(spec, goodValue(spec)), "scene.json", {}))
        << spec.sceneKey << ": " << goodValue(spec);
  }
  EXPECT_GE(checked, 15);
}

TEST(OptionTable, AGivenOptionLandsWhereItsSceneKeyLands) {
  const Json plain = sceneWith(optionSpec("frames"), 10);
  for (const OptionSpec& spec : optionTable()) {
    if (spec.sceneKey.empty()) continue;
    // The option given, over a scene without the key.
    const Json value = spec.kind == OptionKind::Flag ? Json(true) : goodValue(spec);
    GivenOptions given = GivenOptions::object();
    giveOption(given, spec, value);
    SceneFile fromOption = parseScene(plain, "scene.json", {});
    applySceneOptions(given, fromOption);
    // The reference: the value the option lands written into the scene file itself.
    Json file = plain;
    file[sceneKeyPointer(spec)] = spec.kind == OptionKind::Flag ? spec.value : value;
    const SceneFile fromFile = parseScene(file, "scene.json", {});
    EXPECT_EQ(settingsOf(fromOption), settingsOf(fromFile)) << spec.name;
    // --no-render lands the default of a scene file (no PNG), which a built-in scene changes.
    if (spec.name != "no-render") {
      EXPECT_NE(settingsOf(fromOption), settingsOf(parseScene(plain, "scene.json", {})))
          << spec.name << " changed nothing";
    }
  }
}

TEST(OptionTable, CommandLineTextReadsAsTheSceneValue) {
  EXPECT_EQ(optionValueFromText(optionSpec("substeps"), "4"), Json(4));
  EXPECT_EQ(optionValueFromText(optionSpec("substeps"), "auto"), Json("auto"));
  EXPECT_EQ(optionValueFromText(optionSpec("size"), "640x360"), Json::array({640, 360}));
  EXPECT_EQ(optionValueFromText(optionSpec("fps"), "23.976"), Json(23.976));
  EXPECT_EQ(optionValueFromText(optionSpec("levels"), "3x"), Json("3x"));  // refused by the check
  EXPECT_TRUE(checkOptionValue(optionSpec("levels"), Json("3x")));
  EXPECT_EQ(optionWords(optionSpec("size"), Json::array({640, 360})),
            (std::vector<std::string>{"--size", "640x360"}));
  EXPECT_EQ(optionWords(optionSpec("vdb"), true), (std::vector<std::string>{"--vdb"}));
  EXPECT_EQ(optionWords(optionSpec("fps"), 23.976), (std::vector<std::string>{"--fps", "23.976"}));
}

TEST(OptionTable, LoadOptionsLandInTheLoadOptions) {
  GivenOptions given = GivenOptions::object();
  giveOption(given, optionSpec("max-faces"), 12);
  giveOption(given, optionSpec("max-bodies"), 3);
  giveOption(given, optionSpec("accept-lossy-import"), true);
  SceneLoadOptions load;
  applyLoadOptions(given, load);
  EXPECT_EQ(load.maxFaces, std::optional<std::uint64_t>(12));
  EXPECT_EQ(load.maxBodies, 3u);
  EXPECT_TRUE(load.acceptLossyImport);
  EXPECT_FALSE(load.maxVertices);
}

TEST(OptionTable, AValueOutsideTheRangeIsRefusedNamingTheFlag) {
  GivenOptions given = GivenOptions::object();
  try {
    giveOption(given, optionSpec("levels"), 9);
    ADD_FAILURE() << "--levels 9 was taken";
  } catch (const Error& error) {
    EXPECT_STREQ(error.what(), "--levels: expected a whole number from 0 to 8, got 9");
  }
  EXPECT_TRUE(given.empty());
}

}  // namespace
}  // namespace softbake
