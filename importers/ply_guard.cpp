#include "importers/ply_guard.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <fstream>
#include <optional>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

struct PlyType {
  std::string_view name;
  PlyScalar scalar;
  int bytes;
  bool integer;
};

using enum PlyScalar;

// Both spellings of the PLY 1.0 types; assimp 5.2 accepts all of them.
constexpr std::array kTypes = {
    PlyType{"char", kInt8, 1, true},       PlyType{"int8", kInt8, 1, true},
    PlyType{"uchar", kUInt8, 1, true},     PlyType{"uint8", kUInt8, 1, true},
    PlyType{"short", kInt16, 2, true},     PlyType{"int16", kInt16, 2, true},
    PlyType{"ushort", kUInt16, 2, true},   PlyType{"uint16", kUInt16, 2, true},
    PlyType{"int", kInt32, 4, true},       PlyType{"int32", kInt32, 4, true},
    PlyType{"uint", kUInt32, 4, true},     PlyType{"uint32", kUInt32, 4, true},
    PlyType{"float", kFloat32, 4, false},  PlyType{"float32", kFloat32, 4, false},
    PlyType{"double", kFloat64, 8, false}, PlyType{"float64", kFloat64, 8, false},
};

std::optional<PlyType> findType(std::string_view name) {
  for (const PlyType& type : kTypes)
    if (type.name == name) return type;
  return std::nullopt;
}

std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

// Everything a text header may hold; UTF-8 in comments is fine, control bytes are not.
bool isTextLine(std::string_view line) {
  for (char c : line) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && c != '\t') || byte == 0x7f) return false;
  }
  return true;
}

// Exact below 2^53, which every file that exists is.
std::string byteCount(double bytes) {
  if (bytes < 9e15) return cat(std::uint64_t(bytes));
  return cat(bytes);
}

bool isVersion(std::string_view word) {
  // "1.0" is the only version there is; "1" is seen in the wild.
  return word == "1.0" || word == "1";
}

class HeaderParser {
 public:
  HeaderParser(std::string_view source) : source_(source) {}

  [[noreturn]] void fail(int line, std::string_view what) const {
    throw Error(cat(source_, ": PLY header line ", line, ": ", what));
  }
  [[noreturn]] void failHeader(std::string_view what) const {
    throw Error(cat(source_, ": PLY header: ", what));
  }

  // Returns true at end_header.
  bool parseLine(int number, std::string_view line) {
    if (!isTextLine(line)) fail(number, "binary bytes in the header (truncated or corrupt)");
    const std::vector<std::string_view> words = splitWords(line);
    if (number == 1) {
      if (words.size() != 1 || (words[0] != "ply" && words[0] != "PLY"))
        fail(number, "expected 'ply' (not a PLY file)");
      return false;
    }
    if (words.empty()) return false;
    const std::string_view keyword = words[0];
    if (keyword == "comment" || keyword == "obj_info") return false;
    if (keyword == "format") {
      parseFormat(number, words);
    } else if (keyword == "element") {
      parseElement(number, words);
    } else if (keyword == "property") {
      parseProperty(number, words);
    } else if (keyword == "end_header") {
      if (words.size() != 1) fail(number, "unexpected words after 'end_header'");
      finish(number);
      return true;
    } else {
      fail(number, cat("unknown keyword '", keyword, "'"));
    }
    return false;
  }

  PlyHeader& header() { return header_; }

 private:
  void parseFormat(int number, const std::vector<std::string_view>& words) {
    if (hasFormat_) fail(number, "second 'format' line");
    if (!header_.elements.empty()) fail(number, "'format' after the first 'element'");
    if (words.size() != 3)
      fail(number, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    if (words[1] == "ascii") {
      header_.format = PlyFormat::kAscii;
    } else if (words[1] == "binary_little_endian") {
      header_.format = PlyFormat::kBinaryLittleEndian;
    } else if (words[1] == "binary_big_endian") {
      header_.format = PlyFormat::kBinaryBigEndian;
    } else {
      fail(number, cat("unknown format '", words[1],
                       "' (expected ascii, binary_little_endian or binary_big_endian)"));
    }
    if (!isVersion(words[2]))
      fail(number, cat("unsupported version '", words[2], "' (expected 1.0)"));
    hasFormat_ = true;
  }

  void parseElement(int number, const std::vector<std::string_view>& words) {
    if (!hasFormat_) fail(number, "'element' before the 'format' line");
    closeElement();
    if (words.size() != 3) fail(number, "expected 'element <name> <count>'");
    PlyElement element;
    element.name = words[1];
    element.line = number;
    const std::string_view count = words[2];
    const auto [end, error] =
        std::from_chars(count.data(), count.data() + count.size(), element.count);
    if (error != std::errc() || end != count.data() + count.size())
      fail(number,
           cat("element '", words[1], "': count '", count, "' is not a non-negative integer"));
    header_.elements.push_back(std::move(element));
  }

  void parseProperty(int number, const std::vector<std::string_view>& words) {
    if (header_.elements.empty()) fail(number, "'property' before any 'element'");
    PlyElement& element = header_.elements.back();
    if (words.size() >= 2 && words[1] == "list") {
      if (words.size() != 5)
        fail(number, "expected 'property list <count type> <item type> <name>'");
      const std::optional<PlyType> countType = findType(words[2]);
      if (!countType) fail(number, cat("unknown type '", words[2], "'"));
      if (!countType->integer)
        fail(number, cat("list count type '", words[2], "' is not an integer type"));
      const std::optional<PlyType> itemType = findType(words[3]);
      if (!itemType) fail(number, cat("unknown type '", words[3], "'"));
      element.minRowBytes += std::uint64_t(countType->bytes);
      element.fixedSize = false;
      element.properties.push_back(
          {std::string(words[4]), itemType->scalar, true, countType->scalar});
    } else {
      if (words.size() != 3) fail(number, "expected 'property <type> <name>'");
      const std::optional<PlyType> type = findType(words[1]);
      if (!type) fail(number, cat("unknown type '", words[1], "'"));
      element.minRowBytes += std::uint64_t(type->bytes);
      element.properties.push_back({std::string(words[2]), type->scalar});
    }
    ++element.propertyCount;
  }

  void closeElement() const {
    if (header_.elements.empty()) return;
    const PlyElement& last = header_.elements.back();
    // Rows of nothing give a parser no progress to make; no real file has them.
    if (last.propertyCount == 0 && last.count > 0)
      fail(last.line, cat("element '", last.name, "' has ", last.count, " rows but no properties"));
  }

  void finish(int number) const {
    if (!hasFormat_) fail(number, "'end_header' before any 'format' line");
    if (header_.elements.empty()) fail(number, "no 'element' before 'end_header'");
    closeElement();
  }

  std::string_view source_;
  PlyHeader header_;
  bool hasFormat_ = false;
};

}  // namespace

int plyScalarBytes(PlyScalar type) {
  for (const PlyType& known : kTypes)
    if (known.scalar == type) return known.bytes;
  return 0;
}

bool hasPlyMagic(std::string_view firstBytes) {
  if (firstBytes.size() < 3) return false;
  // assimp takes any file opening with these three letters, in either case, for PLY.
  for (std::size_t i = 0; i < 3; ++i)
    if ((firstBytes[i] | 0x20) != "ply"[i]) return false;
  return true;
}

bool isPlyFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<char, 3> first{};
  in.read(first.data(), first.size());
  return hasPlyMagic(std::string_view(first.data(), std::size_t(in.gcount())));
}

PlyHeader parsePlyHeader(std::string_view bytes, std::uint64_t fileSize, std::string_view source) {
  HeaderParser parser(source);
  std::size_t position = 0;
  int number = 0;
  const bool wholeFile = bytes.size() >= fileSize;
  while (true) {
    if (position >= bytes.size()) {
      if (wholeFile)
        parser.failHeader(cat("the file ends after line ", number, " without 'end_header'"));
      parser.fail(number + 1, cat("no 'end_header' within the first ", kMaxPlyHeaderBytes,
                                  " bytes (corrupt header)"));
    }
    const std::size_t newline = bytes.find('\n', position);
    if (newline == std::string_view::npos && !wholeFile)
      parser.fail(number + 1, cat("no 'end_header' within the first ", kMaxPlyHeaderBytes,
                                  " bytes (corrupt header)"));
    const std::size_t end = newline == std::string_view::npos ? bytes.size() : newline;
    std::string_view line = bytes.substr(position, end - position);
    if (line.ends_with('\r')) line.remove_suffix(1);
    ++number;
    const bool ended = parser.parseLine(number, line);
    position = newline == std::string_view::npos ? end : newline + 1;
    if (ended) break;
    if (newline == std::string_view::npos)
      parser.failHeader(cat("the file ends in line ", number, " without 'end_header'"));
  }

  PlyHeader& header = parser.header();
  header.dataOffset = position;
  if (header.format != PlyFormat::kAscii) {
    // Counted in double: a lying count times a row size can overflow 64 bits.
    const double available = double(fileSize - header.dataOffset);
    double needed = 0;
    bool lowerBound = false;  // some rows so far have lists, whose length the header cannot say
    for (const PlyElement& element : header.elements) {
      needed += double(element.count) * double(element.minRowBytes);
      lowerBound |= !element.fixedSize;
      if (needed > available) {
        parser.fail(element.line,
                    cat("element '", element.name, "' does not fit in the file: ", element.count,
                        " × ", element.fixedSize ? "" : "at least ", element.minRowBytes,
                        " bytes bring the binary data to ", lowerBound ? "at least " : "",
                        byteCount(needed), " bytes, but only ", byteCount(available),
                        " follow the header (truncated file)"));
      }
    }
  }
  return header;
}

PlyHeader checkPlyFile(const std::filesystem::path& path) {
  std::error_code error;
  const std::uint64_t fileSize = std::filesystem::file_size(path, error);
  std::ifstream in(path, std::ios::binary);
  if (error || !in) throw Error(cat(path.string(), ": cannot read the file"));
  const std::size_t wanted = std::size_t(std::min<std::uint64_t>(fileSize, kMaxPlyHeaderBytes));
  std::string bytes(wanted, '\0');
  in.read(bytes.data(), std::streamsize(wanted));
  bytes.resize(std::size_t(in.gcount()));
  // A file that shrank while we read it is judged as what we got.
  return parsePlyHeader(bytes, bytes.size() < wanted ? bytes.size() : fileSize, path.string());
}

}  // namespace softbake
