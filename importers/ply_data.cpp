#include "importers/ply_data.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

bool isIntegerType(PlyScalar type) {
  return type != PlyScalar::kFloat32 && type != PlyScalar::kFloat64;
}

bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

template <class T>
double loadBinary(const char* bytes, bool swap) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, bytes, sizeof(T));
  if (swap) std::reverse(raw, raw + sizeof(T));
  T value;
  std::memcpy(&value, raw, sizeof(T));
  return double(value);
}

class Cursor {
 public:
  enum class Status { kOk, kEnd, kBad };

  Cursor(PlyFormat format, std::string_view data)
      : data_(data),
        binary_(format != PlyFormat::kAscii),
        swap_((format == PlyFormat::kBinaryBigEndian) !=
              (std::endian::native == std::endian::big)) {}

  bool binary() const { return binary_; }
  std::uint64_t remaining() const { return data_.size() - position_; }
  void advance(std::uint64_t bytes) { position_ += std::size_t(bytes); }
  std::string_view lastToken() const { return token_; }

  Status read(PlyScalar type, double& value) {
    return binary_ ? readBinary(type, value) : readAscii(type, value);
  }

 private:
  Status readBinary(PlyScalar type, double& value) {
    const auto bytes = std::size_t(plyScalarBytes(type));
    if (remaining() < bytes) return Status::kEnd;
    const char* at = data_.data() + position_;
    position_ += bytes;
    switch (type) {
      case PlyScalar::kInt8:
        value = loadBinary<std::int8_t>(at, swap_);
        break;
      case PlyScalar::kUInt8:
        value = loadBinary<std::uint8_t>(at, swap_);
        break;
      case PlyScalar::kInt16:
        value = loadBinary<std::int16_t>(at, swap_);
        break;
      case PlyScalar::kUInt16:
        value = loadBinary<std::uint16_t>(at, swap_);
        break;
      case PlyScalar::kInt32:
        value = loadBinary<std::int32_t>(at, swap_);
        break;
      case PlyScalar::kUInt32:
        value = loadBinary<std::uint32_t>(at, swap_);
        break;
      case PlyScalar::kFloat32:
        value = loadBinary<float>(at, swap_);
        break;
      case PlyScalar::kFloat64:
        value = loadBinary<double>(at, swap_);
        break;
    }
    return Status::kOk;
  }

  Status readAscii(PlyScalar type, double& value) {
    while (position_ < data_.size() && isSpace(data_[position_])) ++position_;
    if (position_ == data_.size()) return Status::kEnd;
    const std::size_t start = position_;
    while (position_ < data_.size() && !isSpace(data_[position_])) ++position_;
    token_ = data_.substr(start, position_ - start);
    // from_chars takes no '+', which some writers put before exponents' mantissas.
    std::string_view number = token_;
    if (number.size() > 1 && number.front() == '+') number.remove_prefix(1);
    const char* end = number.data() + number.size();
    if (isIntegerType(type)) {
      long long integer = 0;
      const auto [stop, error] = std::from_chars(number.data(), end, integer);
      if (error != std::errc() || stop != end) return Status::kBad;
      value = double(integer);
    } else {
      const auto [stop, error] = std::from_chars(number.data(), end, value);
      if (error != std::errc() || stop != end) return Status::kBad;
    }
    return Status::kOk;
  }

  std::string_view data_;
  std::size_t position_ = 0;
  bool binary_;
  bool swap_;
  std::string_view token_;
};

class RowWalker {
 public:
  // Counting keeps no list items: a lying list length could otherwise hold eight times the
  // file's size in doubles.
  RowWalker(const PlyHeader& header, std::string_view data, std::string_view source, bool keepLists)
      : cursor_(header.format, data), source_(source), keepLists_(keepLists) {}

  Cursor& cursor() { return cursor_; }

  // Reads one row of `element` into row_; false when the data ends within it.
  bool readRow(const PlyElement& element, std::uint64_t index) {
    const std::size_t properties = element.properties.size();
    row_.scalars.assign(properties, 0);
    row_.lists.resize(properties);
    for (std::size_t p = 0; p < properties; ++p) {
      const PlyProperty& property = element.properties[p];
      row_.lists[p].clear();
      if (!property.list) {
        if (!value(element, index, property, property.type, row_.scalars[p])) return false;
        continue;
      }
      double length = 0;
      if (!value(element, index, property, property.countType, length)) return false;
      if (length < 0)
        fail(element, index, property, cat("negative list length ", std::int64_t(length)));
      for (double i = 0; i < length; ++i) {
        double item = 0;
        if (!value(element, index, property, property.type, item)) return false;
        if (keepLists_) row_.lists[p].push_back(item);
      }
    }
    return true;
  }

  const PlyRow& row() const { return row_; }

 private:
  bool value(const PlyElement& element, std::uint64_t index, const PlyProperty& property,
             PlyScalar type, double& out) {
    switch (cursor_.read(type, out)) {
      case Cursor::Status::kOk:
        return true;
      case Cursor::Status::kEnd:
        return false;
      case Cursor::Status::kBad:
        break;
    }
    fail(element, index, property,
         cat("'", cursor_.lastToken(), "' is not ",
             isIntegerType(type) ? "an integer" : "a number"));
  }

  [[noreturn]] void fail(const PlyElement& element, std::uint64_t index,
                         const PlyProperty& property, std::string_view what) const {
    throw Error(cat(source_, ": PLY data: element '", element.name, "' row ", index + 1,
                    " property '", property.name, "': ", what));
  }

  Cursor cursor_;
  std::string_view source_;
  bool keepLists_;
  PlyRow row_;
};

}  // namespace

std::vector<std::uint64_t> countPlyRows(const PlyHeader& header, std::string_view data,
                                        std::string_view source) {
  std::vector<std::uint64_t> counts(header.elements.size(), 0);
  RowWalker walker(header, data, source, /*keepLists=*/false);
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    if (walker.cursor().binary() && element.fixedSize && element.minRowBytes > 0) {
      counts[e] = std::min(element.count, walker.cursor().remaining() / element.minRowBytes);
      walker.cursor().advance(counts[e] * element.minRowBytes);
    } else {
      while (counts[e] < element.count && walker.readRow(element, counts[e])) ++counts[e];
    }
    if (counts[e] < element.count) break;
  }
  return counts;
}

void readPlyRows(const PlyHeader& header, std::string_view data, std::string_view source,
                 const std::function<void(std::size_t, std::uint64_t, const PlyRow&)>& onRow) {
  RowWalker walker(header, data, source, /*keepLists=*/true);
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    for (std::uint64_t r = 0; r < element.count; ++r) {
      if (!walker.readRow(element, r)) return;
      onRow(e, r, walker.row());
    }
  }
}

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path, ": cannot read the file"));
  std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw Error(cat(path, ": cannot read the file"));
  return bytes;
}

}  // namespace softbake
