// Absurd counts in headers and decompression bombs (issue #41): the end of
// file a count runs into names the file, the place, and the element with its
// count and header line (nothing is allocated by the count: reservations are
// capped); gzip input is bounded relative to its compressed size.
#include <gtest/gtest.h>
#include <zlib.h>

#include <string>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/model_reader.h"
#include "tests/fixture_read_error.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::TempDir;
using test::write_text;

using test::read_error;

const char* kPlyHeader =
    "ply\nformat %s 1.0\nelement vertex 99999999999999\nproperty float x\nproperty float y\nproperty float "
    "z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

std::string ply_header(const char* format) {
  char text[512];
  std::snprintf(text, sizeof text, kPlyHeader, format);
  return text;
}

TEST(InputLimits, AbsurdPlyElementCountsNameTheElementCountAndHeaderLine) {
  TempDir dir;
  write_text(dir / "a.ply", ply_header("ascii") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  write_text(dir / "b.ply", ply_header("binary_little_endian") + std::string(40, '\0'));
  EXPECT_NE(
      read_error(dir / "a.ply")
          .find("a.ply:line 13: unexpected end of file in element vertex (count 99999999999999, line 3)"),
      std::string::npos)
      << read_error(dir / "a.ply");
  EXPECT_NE(
      read_error(dir / "b.ply")
          .find("b.ply:byte 218: unexpected end of file in element vertex (count 99999999999999, line 3)"),
      std::string::npos)
      << read_error(dir / "b.ply");
  // A face count the file cannot hold either, named as such.
  write_text(
      dir / "c.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
      "3 0 1 2");
  EXPECT_NE(read_error(dir / "c.ply")
                .find("c.ply:line 13: unexpected end of file in element face (count 4000000000, line 7)"),
            std::string::npos)
      << read_error(dir / "c.ply");
}

TEST(InputLimits, FilesThatHoldTheirCountsStillReadWithoutAFinalNewline) {
  TempDir dir;
  write_text(
      dir / "a.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  write_text(dir / "a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  for (const char* name : {"a.ply", "a.off"}) {
    std::uint64_t triangles = 0;
    EXPECT_EQ(read_error(dir / name, &triangles), "") << name;
    EXPECT_EQ(triangles, 1u) << name;
  }
}

TEST(InputLimits, AbsurdOffAndStlCountsNameTheCountsAndTheirLine) {
  TempDir dir;
  write_text(dir / "a.off", "OFF\n99999999999999 99999999999999 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(read_error(dir / "a.off")
                .find("a.off:line 6: unexpected end of file in vertex 4 (vertex count 99999999999999, face "
                      "count 99999999999999, line 2)"),
            std::string::npos)
      << read_error(dir / "a.off");
  std::string stl(80, '\0');
  stl += std::string{'\0', char(0x28), char(0x6B), char(0xEE)};  // 4,000,000,000 triangles, little endian
  stl += std::string(50, '\0');
  write_text(dir / "a.stl", stl);
  EXPECT_NE(read_error(dir / "a.stl").find("a.stl:byte 80: binary STL header announces 4000000000 triangles"),
            std::string::npos)
      << read_error(dir / "a.stl");
}

TEST(InputLimits, AGzipBombIsRefusedBeforeItsVertexTableGrows) {
  TempDir dir;
  // A 10-million-vertex PLY of zeros: 120 MB that gzip (run-length) packs into ~1 MB.
  gzFile gz = gzopen((dir / "bomb.ply.gz").c_str(), "wb1R");
  ASSERT_NE(gz, nullptr);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 10000000\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  gzwrite(gz, header.data(), unsigned(header.size()));
  const std::vector<char> zeros(std::size_t{1} << 20, 0);
  for (int i = 0; i < 115; ++i) gzwrite(gz, zeros.data(), unsigned(zeros.size()));
  gzclose(gz);
  const std::string error = read_error(dir / "bomb.ply.gz");
  EXPECT_NE(error.find("bomb.ply.gz:byte "), std::string::npos) << error;
  EXPECT_NE(error.find("gzip data decompresses to more than 67108864 bytes"), std::string::npos) << error;
  EXPECT_NE(error.find("decompression bomb"), std::string::npos) << error;
}

}  // namespace
}  // namespace cellbake
