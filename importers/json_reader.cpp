#include "importers/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

std::string keyPath(std::string_view parent, std::string_view key) {
  return parent.empty() ? std::string(key) : cat(parent, '.', key);
}

std::string indexPath(std::string_view parent, std::size_t index) {
  return cat(parent, '[', index, ']');
}

// Edits (insert, delete, replace, swap two neighbours) that turn a into b: "fsp" is one from "fps".
std::size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min(
          {d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1] ? 1 : 0)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// Tracks where the parser is, so a repeated key can be reported with its object's key path.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(std::string_view source) : source_(source) {}

  bool operator()(int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    switch (event) {
      case Event::object_start:
      case Event::array_start:
        frames_.push_back({event == Event::array_start, 0, {}, nextPath(), {}});
        break;
      case Event::object_end:
      case Event::array_end:
        frames_.pop_back();
        break;
      case Event::key: {
        Frame& frame = frames_.back();
        frame.lastKey = parsed.get<std::string>();
        if (!frame.keys.insert(frame.lastKey).second) {
          const std::string where = frame.path.empty() ? std::string() : cat(frame.path, ": ");
          throw Error(cat(source_, ": ", where, "duplicate key '", frame.lastKey, "'"));
        }
        break;
      }
      case Event::value:
        nextPath();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array;
    std::size_t nextIndex;
    std::set<std::string> keys;
    std::string path;
    std::string lastKey;
  };

  // The path of the value that starts now; advances the enclosing array's index.
  std::string nextPath() {
    if (frames_.empty()) return {};
    Frame& parent = frames_.back();
    if (parent.array) return indexPath(parent.path, parent.nextIndex++);
    return keyPath(parent.path, parent.lastKey);
  }

  std::string_view source_;
  std::vector<Frame> frames_;
};

// "line 3, column 5" of the character at `offset`.
std::string lineAndColumn(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return cat("line ", line, ", column ", column);
}

// nlohmann's messages start "[json.exception.parse_error.101] "; the rest is for the user.
std::string withoutExceptionId(std::string message) {
  if (message.starts_with("[json.exception.")) {
    const std::size_t end = message.find("] ");
    if (end != std::string::npos) message.erase(0, end + 2);
  }
  return message;
}

}  // namespace

nlohmann::json parseJsonText(std::string_view text, std::string_view source) {
  try {
    return nlohmann::json::parse(text.begin(), text.end(), DuplicateKeyCheck(source),
                                 /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& error) {
    // error.byte is one past the character that broke the parse. nlohmann's message is "parse
    // error at line 3, column 5: <description>"; keep the description only.
    std::string description = withoutExceptionId(error.what());
    const std::size_t columnAt = description.find(", column ");
    const std::size_t colon = description.find(": ", columnAt == std::string::npos ? 0 : columnAt);
    if (colon != std::string::npos) description.erase(0, colon + 2);
    throw Error(cat(source, ": ", lineAndColumn(text, error.byte > 0 ? error.byte - 1 : 0),
                    ": invalid JSON: ", description));
  } catch (const nlohmann::json::exception& error) {
    // A number too large for a double ("number overflow parsing '1e400'", found by fuzzing: it
    // used to escape as nlohmann's own exception and abort the program). nlohmann says not
    // where, so the number's text is looked up.
    const std::string description = withoutExceptionId(error.what());
    std::string where;
    const std::size_t open = description.find('\'');
    const std::size_t close = description.rfind('\'');
    if (open != std::string::npos && close > open + 1) {
      const std::size_t at = text.find(description.substr(open + 1, close - open - 1));
      if (at != std::string_view::npos) where = cat(lineAndColumn(text, at), ": ");
    }
    throw Error(cat(source, ": ", where, "invalid JSON: ", description));
  }
}

nlohmann::json readJsonFile(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw Error(cat(path.string(), ": file not found"));
  if (std::filesystem::is_directory(path, error))
    throw Error(cat(path.string(), ": is a directory, not a JSON file"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path.string(), ": cannot open the file"));
  std::ostringstream text;
  text << in.rdbuf();
  return parseJsonText(text.str(), path.string());
}

JsonValue::JsonValue(const nlohmann::json& value, std::string_view source, std::string path)
    : value_(&value), source_(source), path_(std::move(path)) {}

void JsonValue::fail(std::string_view what) const {
  if (path_.empty()) throw Error(cat(source_, ": ", what));
  throw Error(cat(source_, ": ", path_, ": ", what));
}

bool JsonValue::isString() const {
  return value_->is_string();
}

bool JsonValue::isObject() const {
  return value_->is_object();
}

std::string JsonValue::string() const {
  if (!value_->is_string()) fail("expected string");
  return value_->get<std::string>();
}

bool JsonValue::boolean() const {
  if (!value_->is_boolean()) fail("expected boolean");
  return value_->get<bool>();
}

double JsonValue::number() const {
  if (!value_->is_number()) fail("expected number");
  return value_->get<double>();
}

double JsonValue::numberAbove(double lowest) const {
  const double x = number();
  if (!(x > lowest)) fail(cat("expected a number > ", lowest));
  return x;
}

double JsonValue::numberAtLeast(double lowest) const {
  const double x = number();
  if (!(x >= lowest)) fail(cat("expected a number >= ", lowest));
  return x;
}

double JsonValue::numberIn(double lowest, double highest) const {
  const double x = number();
  if (!(x >= lowest && x <= highest))
    fail(cat("expected a number in [", lowest, ", ", highest, "]"));
  return x;
}

long long JsonValue::integer() const {
  if (value_->is_number_integer()) {
    if (value_->is_number_unsigned() &&
        value_->get<unsigned long long>() > std::uint64_t(std::numeric_limits<long long>::max()))
      return std::numeric_limits<long long>::max();
    return value_->get<long long>();
  }
  // 24.0 is an integer too; 24.5 is not.
  if (value_->is_number_float()) {
    const double x = value_->get<double>();
    if (x == std::floor(x) && std::abs(x) < 9e18) return static_cast<long long>(x);
  }
  fail("expected integer");
}

long long JsonValue::integerAtLeast(long long lowest) const {
  const long long x = integer();
  if (x < lowest) fail(cat("expected an integer >= ", lowest));
  return x;
}

long long JsonValue::integerIn(long long lowest, long long highest) const {
  const long long x = integer();
  if (x < lowest || x > highest) fail(cat("expected an integer in [", lowest, ", ", highest, "]"));
  return x;
}

Eigen::Vector3d JsonValue::vector3() const {
  if (!value_->is_array() || value_->size() != 3) fail("expected array of 3 numbers");
  return {element(0).number(), element(1).number(), element(2).number()};
}

std::vector<JsonValue> JsonValue::array() const {
  if (!value_->is_array()) fail("expected array");
  std::vector<JsonValue> elements;
  elements.reserve(value_->size());
  for (std::size_t i = 0; i < value_->size(); ++i) elements.push_back(element(i));
  return elements;
}

JsonObject JsonValue::object(std::initializer_list<std::string_view> keys) const {
  if (!value_->is_object()) fail("expected object");
  for (const auto& [key, unused] : value_->items()) {
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    std::string_view closest;
    std::size_t best = std::numeric_limits<std::size_t>::max();
    for (std::string_view known : keys) {
      const std::size_t distance = editDistance(key, known);
      if (distance < best) {
        best = distance;
        closest = known;
      }
    }
    // A suggestion only for what looks like a typo (at most one edit in two characters);
    // otherwise list every valid key.
    if (2 * best <= std::max(key.size(), closest.size())) {
      fail(cat("unknown key '", key, "' (did you mean '", closest, "'?)"));
    }
    std::string valid;
    for (std::string_view known : keys) valid += cat(valid.empty() ? "" : ", ", known);
    fail(cat("unknown key '", key, "' (valid keys: ", valid, ")"));
  }
  return JsonObject(*this);
}

JsonValue JsonValue::child(std::string_view key) const {
  return JsonValue(value_->at(std::string(key)), source_, keyPath(path_, key));
}

JsonValue JsonValue::element(std::size_t index) const {
  return JsonValue(value_->at(index), source_, indexPath(path_, index));
}

bool JsonObject::contains(std::string_view key) const {
  return value_.raw().contains(key);
}

std::optional<JsonValue> JsonObject::find(std::string_view key) const {
  if (!contains(key)) return std::nullopt;
  return value_.child(key);
}

JsonValue JsonObject::at(std::string_view key) const {
  if (!contains(key)) value_.fail(cat("missing key '", key, "'"));
  return value_.child(key);
}

}  // namespace softbake
