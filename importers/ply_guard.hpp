#pragma once
/// A strict check of PLY headers, run before assimp sees a PLY file.
///
/// assimp 5.2's PLY parser trusts the header: a truncated or corrupt one (such as
/// shared/meshes/broken/crash-30d6….ply) makes it read out of bounds and take the whole process
/// down. Checking the header and the declared data size first turns that into a clear error.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace softbake {

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// The value types of PLY 1.0 (each under both of its names: char and int8, …).
enum class PlyScalar { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

/// Bytes of one binary value of `type`.
int plyScalarBytes(PlyScalar type);

struct PlyProperty {
  std::string name;
  PlyScalar type = PlyScalar::kFloat32;  ///< of the value, or of a list's items
  bool list = false;
  PlyScalar countType = PlyScalar::kUInt8;  ///< of a list's length; an integer type
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t propertyCount = 0;
  /// Bytes of one binary row with every list empty: a lower bound for elements with lists.
  std::uint64_t minRowBytes = 0;
  bool fixedSize = true;  ///< no list properties: every binary row is exactly minRowBytes
  int line = 0;           ///< header line of the `element` keyword, 1-based
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::uint64_t dataOffset = 0;  ///< first byte after `end_header`
};

/// Headers longer than this are taken for garbage: real ones are a few hundred bytes, and even
/// long comment blocks stay far below it.
inline constexpr std::size_t kMaxPlyHeaderBytes = 64 * 1024;

/// Whether a file's first bytes make assimp read it as PLY: "ply" in either case. That covers
/// "ply\n" and "ply\r\n", and also openings like "plyx" that the header check then rejects.
bool hasPlyMagic(std::string_view firstBytes);

/// Whether the file at `path` opens like a PLY file, whatever its extension.
bool isPlyFile(const std::filesystem::path& path);

/// Validates a PLY header. `bytes` holds the start of the file (up to kMaxPlyHeaderBytes, or all of
/// it when shorter) and `fileSize` its full size. Throws softbake::Error starting with `source`
/// and naming the header line that is wrong:
/// "x.ply: PLY header line 7: binary bytes in the header (truncated or corrupt)".
PlyHeader parsePlyHeader(std::string_view bytes, std::uint64_t fileSize, std::string_view source);

/// parsePlyHeader() on the file at `path`, named by its path in messages.
PlyHeader checkPlyFile(const std::filesystem::path& path);

}  // namespace softbake
