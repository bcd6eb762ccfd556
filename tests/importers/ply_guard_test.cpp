// The PLY header check. The crash file from tests/data/meshes/broken is only ever given to the
// guard here: assimp 5.2 itself would take the test process down with it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>

#include "core/error.hpp"
#include "generated_meshes.hpp"
#include "importers/ply_guard.hpp"
#include "test_files.hpp"

namespace softbake {
namespace {

using ::testing::StartsWith;

std::string guardError(std::string_view bytes, std::uint64_t fileSize) {
  try {
    parsePlyHeader(bytes, fileSize, "t.ply");
  } catch (const Error& error) {
    return error.what();
  }
  return "(accepted)";
}

std::string guardError(std::string_view bytes) {
  return guardError(bytes, bytes.size());
}

TEST(PlyGuard, RejectsTheCrashFileWithoutAssimp) {
  const auto file =
      test::testMeshes() / "broken" / "crash-30d6d0f7c529b3b66b4131700b7a4580cd7082df.ply";
  ASSERT_TRUE(isPlyFile(file));
  try {
    checkPlyFile(file);
    FAIL() << "the crash file passed the guard";
  } catch (const Error& error) {
    // Line 7 is "property " followed by binary garbage: the header was cut off there.
    EXPECT_EQ(
        std::string(error.what()),
        file.string() + ": PLY header line 7: binary bytes in the header (truncated or corrupt)");
  }
}

TEST(PlyGuard, AcceptsTheTestPlyFiles) {
  test::ScratchDir dir;
  const PlyHeader scan = checkPlyFile(dir.write("scan.ply", test::ScanPly::text()));
  EXPECT_EQ(scan.format, PlyFormat::kAscii);
  ASSERT_EQ(scan.elements.size(), 2u);
  EXPECT_EQ(scan.elements[0].name, "vertex");
  EXPECT_EQ(scan.elements[0].count, test::ScanPly::kFileVertices);
  EXPECT_EQ(scan.elements[0].propertyCount, 5u);  // x y z confidence intensity
  EXPECT_EQ(scan.elements[1].count, test::ScanPly::kTriangles);
  EXPECT_FALSE(scan.elements[1].fixedSize);

  const auto fuzeFile = test::testMeshes() / "fuze.ply";
  const PlyHeader fuze = checkPlyFile(fuzeFile);
  EXPECT_EQ(fuze.format, PlyFormat::kBinaryLittleEndian);
  ASSERT_EQ(fuze.elements.size(), 2u);
  EXPECT_EQ(fuze.elements[0].count, 502u);
  EXPECT_EQ(fuze.elements[0].minRowBytes, 3 * 4 + 4 * 1u);  // xyz floats, rgba bytes
  EXPECT_TRUE(fuze.elements[0].fixedSize);
  EXPECT_EQ(fuze.elements[1].count, 1000u);
  EXPECT_LE(fuze.dataOffset + 502 * 16 + 1000 * fuze.elements[1].minRowBytes,
            std::filesystem::file_size(fuzeFile));
}

TEST(PlyGuard, RecognisesPlyByItsFirstBytes) {
  EXPECT_TRUE(hasPlyMagic("ply\nformat ascii 1.0\n"));
  EXPECT_TRUE(hasPlyMagic("ply\r\nformat ascii 1.0\r\n"));
  EXPECT_TRUE(hasPlyMagic("PLY\n"));  // assimp reads these too, so they are checked too
  EXPECT_FALSE(hasPlyMagic("pl"));
  EXPECT_FALSE(hasPlyMagic(""));
  EXPECT_FALSE(hasPlyMagic("solid ply\n"));
  EXPECT_FALSE(hasPlyMagic("# ply\n"));

  test::ScratchDir dir;
  EXPECT_TRUE(isPlyFile(dir.write("disguised.txt", "ply\nformat ascii 1.0\n")));
  EXPECT_FALSE(isPlyFile(dir.write("real.obj", "v 0 0 0\n")));
  EXPECT_FALSE(isPlyFile(dir / "missing.ply"));
}

constexpr std::string_view kTriangle =
    "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\n"
    "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

TEST(PlyGuard, AcceptsWellFormedHeaders) {
  const PlyHeader header = parsePlyHeader(kTriangle, kTriangle.size(), "t.ply");
  EXPECT_EQ(header.elements.size(), 2u);
  EXPECT_EQ(header.dataOffset, kTriangle.find("0 0 0"));
  EXPECT_EQ(header.elements[1].line, 8);

  std::string crlf;
  for (char c : kTriangle) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  EXPECT_EQ(guardError(crlf), "(accepted)");

  // Both type spellings, tabs, blank lines, obj_info, and end_header as the file's last bytes.
  EXPECT_EQ(guardError("ply\nformat binary_big_endian 1.0\nobj_info x\n\nelement v 0\n"
                       "property\tfloat32 x\nproperty uint8 y\nelement f 0\n"
                       "property list uint16 int32 i\nend_header"),
            "(accepted)");
}

TEST(PlyGuard, NamesTheLineAndWhatIsWrong) {
  struct Case {
    std::string header;
    std::string error;
  };
  const std::string start = "ply\nformat ascii 1.0\n";
  const std::vector<Case> cases = {
      {"plyx\n", "t.ply: PLY header line 1: expected 'ply' (not a PLY file)"},
      {"ply\nformat ascii\nend_header\n",
       "t.ply: PLY header line 2: expected 'format <ascii|binary_little_endian|binary_big_endian> "
       "1.0'"},
      {"ply\nformat binary_middle_endian 1.0\n",
       "t.ply: PLY header line 2: unknown format 'binary_middle_endian' (expected ascii, "
       "binary_little_endian or binary_big_endian)"},
      {"ply\nformat ascii 2.0\n",
       "t.ply: PLY header line 2: unsupported version '2.0' (expected 1.0)"},
      {start + "format ascii 1.0\n", "t.ply: PLY header line 3: second 'format' line"},
      {"ply\nelement vertex 3\n", "t.ply: PLY header line 2: 'element' before the 'format' line"},
      {start + "element vertex\n", "t.ply: PLY header line 3: expected 'element <name> <count>'"},
      {start + "element vertex -3\n",
       "t.ply: PLY header line 3: element 'vertex': count '-3' is not a non-negative integer"},
      {start + "element vertex 3x\n",
       "t.ply: PLY header line 3: element 'vertex': count '3x' is not a non-negative integer"},
      {start + "element vertex 99999999999999999999999\n",
       "t.ply: PLY header line 3: element 'vertex': count '99999999999999999999999' is not a "
       "non-negative integer"},
      {start + "property float x\n", "t.ply: PLY header line 3: 'property' before any 'element'"},
      {start + "element vertex 1\nproperty float\n",
       "t.ply: PLY header line 4: expected 'property <type> <name>'"},
      {start + "element vertex 1\nproperty real x\n",
       "t.ply: PLY header line 4: unknown type 'real'"},
      {start + "element face 1\nproperty list int\n",
       "t.ply: PLY header line 4: expected 'property list <count type> <item type> <name>'"},
      {start + "element face 1\nproperty list float int i\n",
       "t.ply: PLY header line 4: list count type 'float' is not an integer type"},
      {start + "element face 1\nproperty list uchar bits i\n",
       "t.ply: PLY header line 4: unknown type 'bits'"},
      {start + "element vertex 1\nproperty float x\nelements 3\n",
       "t.ply: PLY header line 5: unknown keyword 'elements'"},
      {start + "element vertex 2\nelement face 1\nproperty list uchar int i\nend_header\n",
       "t.ply: PLY header line 3: element 'vertex' has 2 rows but no properties"},
      {start + "end_header\n", "t.ply: PLY header line 3: no 'element' before 'end_header'"},
      {"ply\nend_header\n", "t.ply: PLY header line 2: 'end_header' before any 'format' line"},
      {start + "element vertex 1\nproperty float x\nend_header extra\n",
       "t.ply: PLY header line 5: unexpected words after 'end_header'"},
      {start + "element vertex 1\nproperty float x\n",
       "t.ply: PLY header: the file ends after line 4 without 'end_header'"},
      {start + "element vertex 1\nproperty float x",
       "t.ply: PLY header: the file ends in line 4 without 'end_header'"},
      {start + "comment \x01\x02\n",
       "t.ply: PLY header line 3: binary bytes in the header (truncated or corrupt)"},
  };
  for (const Case& c : cases) EXPECT_EQ(guardError(c.header), c.error) << c.header;
}

TEST(PlyGuard, GivesUpOnHeadersLongerThanTheLimit) {
  std::string bytes = "ply\nformat ascii 1.0\n";
  while (bytes.size() < kMaxPlyHeaderBytes) bytes += "comment padding padding padding padding\n";
  bytes.resize(kMaxPlyHeaderBytes);
  EXPECT_THAT(guardError(bytes, kMaxPlyHeaderBytes + 1000),
              ::testing::MatchesRegex("t\\.ply: PLY header line [0-9]+: no 'end_header' within the "
                                      "first 65536 bytes \\(corrupt header\\)"));
}

std::string binaryPly(std::size_t vertices, std::size_t dataBytes) {
  std::string file = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                     std::to_string(vertices) +
                     "\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  file.append(dataBytes, '\0');
  return file;
}

TEST(PlyGuard, BinaryDataMustBeAsLongAsTheHeaderSays) {
  // 3 vertices of 12 bytes, then a face of at least its 1-byte count.
  EXPECT_EQ(guardError(binaryPly(3, 36 + 1)), "(accepted)");
  EXPECT_EQ(
      guardError(binaryPly(3, 36)),
      "t.ply: PLY header line 7: element 'face' does not fit in the file: 1 × at least 1 bytes "
      "bring the binary data to at least 37 bytes, but only 36 follow the header (truncated "
      "file)");
  EXPECT_EQ(
      guardError(binaryPly(3, 35)),
      "t.ply: PLY header line 3: element 'vertex' does not fit in the file: 3 × 12 bytes bring "
      "the binary data to 36 bytes, but only 35 follow the header (truncated file)");
  // Counts that would overflow 64 bits when multiplied out are still caught.
  EXPECT_THAT(guardError(binaryPly(std::size_t(1) << 62, 100)),
              StartsWith("t.ply: PLY header line 3: element 'vertex' does not fit in the file"));
}

}  // namespace
}  // namespace softbake
