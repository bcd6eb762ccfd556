// The key-path-aware JSON walker under the scene parser.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "importers/json_reader.hpp"

namespace softbake {
namespace {

template <class Read>
std::string jsonErrorOf(Read read) {
  try {
    read();
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

std::string parseError(std::string_view text) {
  return jsonErrorOf([&] { parseJsonText(text, "scene.json"); });
}

TEST(JsonReader, SyntaxErrorsNameLineAndColumn) {
  EXPECT_EQ(parseError("{\n  \"a\": 1,\n  \"b\": }\n"),
            "scene.json: line 3, column 8: invalid JSON: syntax error while parsing value - "
            "unexpected '}'; expected '[', '{', or a literal");
  EXPECT_THAT(parseError("{\"a\": [1, 2}"),
              ::testing::StartsWith("scene.json: line 1, column 12: invalid JSON: "));
  EXPECT_THAT(parseError(""),
              ::testing::StartsWith("scene.json: line 1, column 1: invalid JSON: "));
}

// Found by fuzzing: nlohmann reports a number too large for a double as an out_of_range
// exception, which escaped the reader and aborted the program.
TEST(JsonReader, NumbersTooLargeForADoubleAreSyntaxErrorsWithTheirPlace) {
  EXPECT_EQ(parseError("{\n  \"fps\": 1e400\n}\n"),
            "scene.json: line 2, column 10: invalid JSON: number overflow parsing '1e400'");
  EXPECT_EQ(parseError("[-5555000124091491e3085639778]"),
            "scene.json: line 1, column 2: invalid JSON: number overflow parsing "
            "'-5555000124091491e3085639778'");
}

TEST(JsonReader, AllowsComments) {
  const nlohmann::json json =
      parseJsonText("{ // the frame rate\n \"fps\": 30 /* per second */ }", "s");
  EXPECT_EQ(json.at("fps"), 30);
}

TEST(JsonReader, RepeatedKeysAreErrorsWithTheirPath) {
  EXPECT_EQ(parseError(R"({"fps": 24, "fps": 30})"), "scene.json: duplicate key 'fps'");
  EXPECT_EQ(parseError(R"({"bodies": [{"mass": 1}, {"v": [1, {"a": 1}], "mass": 1, "mass": 2}]})"),
            "scene.json: bodies[1]: duplicate key 'mass'");
  EXPECT_EQ(parseError(R"({"a": {"b": [0, 1, {"c": 1, "c": 2}]}})"),
            "scene.json: a.b[2]: duplicate key 'c'");
  // The same key in sibling objects is fine.
  EXPECT_EQ(parseError(R"([{"a": 1}, {"a": 2}, {"b": {"a": 3}}])"), "(no error)");
}

TEST(JsonReader, TypeAndRangeErrorsNameTheKeyPath) {
  const nlohmann::json json = nlohmann::json::parse(
      R"({"n": -2, "s": "x", "i": 2.5, "big": 12, "v": [1, "y", 3], "flag": 1, "whole": 4.0})");
  const JsonValue root(json, "scene.json", "");
  const JsonObject object = root.object({"n", "s", "i", "big", "v", "flag", "whole"});
  EXPECT_EQ(jsonErrorOf([&] { object.at("s").number(); }), "scene.json: s: expected number");
  EXPECT_EQ(jsonErrorOf([&] { object.at("n").string(); }), "scene.json: n: expected string");
  EXPECT_EQ(jsonErrorOf([&] { object.at("n").numberAbove(0); }),
            "scene.json: n: expected a number > 0");
  EXPECT_EQ(jsonErrorOf([&] { object.at("n").numberAtLeast(0.5); }),
            "scene.json: n: expected a number >= 0.5");
  EXPECT_EQ(jsonErrorOf([&] { object.at("n").numberIn(0, 1); }),
            "scene.json: n: expected a number in [0, 1]");
  EXPECT_EQ(jsonErrorOf([&] { object.at("i").integerAtLeast(0); }),
            "scene.json: i: expected integer");
  EXPECT_EQ(jsonErrorOf([&] { object.at("big").integerIn(1, 9); }),
            "scene.json: big: expected an integer in [1, 9]");
  EXPECT_EQ(object.at("whole").integerIn(1, 9), 4);
  EXPECT_EQ(jsonErrorOf([&] { object.at("v").vector3(); }), "scene.json: v[1]: expected number");
  EXPECT_EQ(jsonErrorOf([&] { object.at("s").vector3(); }),
            "scene.json: s: expected array of 3 numbers");
  EXPECT_EQ(jsonErrorOf([&] { object.at("flag").boolean(); }),
            "scene.json: flag: expected boolean");
  EXPECT_EQ(jsonErrorOf([&] { object.at("s").array(); }), "scene.json: s: expected array");
  EXPECT_EQ(jsonErrorOf([&] { object.at("s").object({}); }), "scene.json: s: expected object");
  EXPECT_EQ(jsonErrorOf([&] { object.at("missing"); }), "scene.json: missing key 'missing'");
  EXPECT_EQ(jsonErrorOf([&] { object.value().child("v").element(0).object({}); }),
            "scene.json: v[0]: expected object");
}

TEST(JsonReader, UnknownKeysSuggestTheClosestOrListAll) {
  const nlohmann::json json = nlohmann::json::parse(R"({"m": {"stifness": 1}, "q": {"zzz": 1}})");
  const JsonValue root(json, "scene.json", "");
  EXPECT_EQ(jsonErrorOf([&] { root.object({"m"}); }),
            "scene.json: unknown key 'q' (valid keys: m)");
  const JsonValue m = root.object({"m", "q"}).at("m");
  EXPECT_EQ(jsonErrorOf([&] {
              m.object({"preset", "stiffness", "damping"});
            }),
            "scene.json: m: unknown key 'stifness' (did you mean 'stiffness'?)");
  const JsonValue q = root.object({"m", "q"}).at("q");
  EXPECT_EQ(jsonErrorOf([&] {
              q.object({"preset", "stiffness"});
            }),
            "scene.json: q: unknown key 'zzz' (valid keys: preset, stiffness)");
}

}  // namespace
}  // namespace softbake
