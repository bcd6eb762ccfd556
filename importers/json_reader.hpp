#pragma once
/// Strict reading of JSON documents that knows where it is: every value carries its file and key
/// path, so any error can say exactly which value is wrong:
/// "scene.json: bodies[1].material.stiffness: expected number".

#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

namespace softbake {

/// Parses JSON text (comments allowed). Throws softbake::Error for a syntax error, naming `source`
/// with the line and column, and for a key repeated within one object, which JSON parsers
/// otherwise resolve silently by keeping the last.
nlohmann::json parseJsonText(std::string_view text, std::string_view source);

/// parseJsonText() on a file's contents; `path` names it in messages.
nlohmann::json readJsonFile(const std::filesystem::path& path);

class JsonObject;

/// A value in a document and where it is. Cheap to copy; it refers to the document.
class JsonValue {
 public:
  JsonValue(const nlohmann::json& value, std::string_view source, std::string path);

  const nlohmann::json& raw() const { return *value_; }
  const std::string& path() const { return path_; }
  std::string_view source() const { return source_; }

  /// Throws softbake::Error "<source>: <path>: <what>".
  [[noreturn]] void fail(std::string_view what) const;

  bool isString() const;
  bool isObject() const;

  std::string string() const;
  bool boolean() const;
  double number() const;
  double numberAbove(double lowest) const;    ///< > lowest
  double numberAtLeast(double lowest) const;  ///< >= lowest
  double numberIn(double lowest, double highest) const;
  long long integerAtLeast(long long lowest) const;
  long long integerIn(long long lowest, long long highest) const;
  Eigen::Vector3d vector3() const;  ///< an array of exactly three numbers
  std::vector<JsonValue> array() const;
  /// The value as an object whose keys must all be among `keys`; anything else is reported as
  /// "unknown key 'x'", with the closest known key as a suggestion.
  JsonObject object(std::initializer_list<std::string_view> keys) const;

  JsonValue child(std::string_view key) const;
  JsonValue element(std::size_t index) const;

 private:
  long long integer() const;

  const nlohmann::json* value_;
  std::string_view source_;
  std::string path_;
};

/// An object whose keys have been checked against the known ones.
class JsonObject {
 public:
  explicit JsonObject(JsonValue value) : value_(std::move(value)) {}

  const JsonValue& value() const { return value_; }
  bool contains(std::string_view key) const;
  /// The value under `key`, or nothing when the key is absent.
  std::optional<JsonValue> find(std::string_view key) const;
  /// The value under `key`; its absence is an error: "bodies[0]: missing key 'mesh'".
  JsonValue at(std::string_view key) const;

 private:
  JsonValue value_;
};

}  // namespace softbake
