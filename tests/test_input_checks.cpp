// Model input checks (issue #14, items 11-12): binary STL counts, missing
// mtllib warnings, non-regular files, ASCII PLY line numbers, GLB chunk
// lengths checked before assimp allocates them.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstring>

#include "pipeline/ingest.h"
#include "pipeline/readers/model_reader.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

std::string read_error(const std::filesystem::path& file) {
  try {
    read_model(file, [](const Triangle&) {});
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

std::string binary_stl(std::uint32_t declared, std::uint32_t actual) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&declared), 4);
  for (std::uint32_t i = 0; i < actual; ++i) {
    float rec[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, float(i)};
    s.append(reinterpret_cast<const char*>(rec), 48);
    s.append(2, '\0');
  }
  return s;
}

TEST(InputChecks, BinaryStlWithMoreRecordsThanItsHeaderSaysIsAnError) {
  test::TempDir dir;
  test::write_text(dir / "more.stl", binary_stl(2, 5));
  const std::string e = read_error(dir / "more.stl");
  EXPECT_NE(e.find("more.stl:byte 80: binary STL header announces 2 triangles (184 bytes) but the file has 334 bytes "
                   "(5 whole triangle records)"),
            std::string::npos)
      << e;
  test::write_text(dir / "exact.stl", binary_stl(5, 5));
  EXPECT_EQ(read_error(dir / "exact.stl"), "(no error)");
}

TEST(InputChecks, DirectoriesAndPipesAreNotRegularFiles) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "folder.obj");
  ASSERT_EQ(mkfifo((dir / "pipe.obj").c_str(), 0600), 0);
  EXPECT_NE(read_error(dir / "folder.obj").find("not a regular file (a directory)"), std::string::npos);
  EXPECT_NE(read_error(dir / "pipe.obj").find("not a regular file (a pipe)"), std::string::npos);
  EXPECT_NE(read_error(dir / "absent.obj").find("no such file"), std::string::npos);
  const auto cli = test::run_cellbake("ingest " + (dir / "pipe.obj").string() + " --store " + (dir / "s.db").string());
  EXPECT_NE(cli.exit_code, 0);
  EXPECT_NE(cli.output.find("pipe.obj: not a regular file (a pipe)"), std::string::npos) << cli.output;
}

TEST(InputChecks, AsciiPlyShortVertexLineIsReportedAtItsLine) {
  test::TempDir dir;
  test::write_text(dir / "short.ply",
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n1 0\n0 1 0\n3 0 1 2\n");
  const std::string e = read_error(dir / "short.ply");
  EXPECT_NE(e.find("short.ply:line 11: vertex 1: fewer values on the line than the element's 3 properties"),
            std::string::npos)
      << e;
}

TEST(InputChecks, AMissingMtllibIsACountedWarning) {
  test::TempDir dir;
  test::write_text(dir / "m.obj", "mtllib absent.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const IngestReport r = ingest_models({dir / "m.obj"}, dir / "s.db", IngestParams{},
                                       [](std::size_t n, const std::function<void(std::size_t)>& fn) {
                                         for (std::size_t i = 0; i < n; ++i) fn(i);
                                       });
  ASSERT_EQ(r.input_warnings.size(), 1u);
  EXPECT_EQ(r.input_warnings[0], "m.obj:line 1: mtllib 'absent.mtl': missing or unreadable; its materials are default grey");
  const auto cli = test::run_cellbake("ingest " + (dir / "m.obj").string() + " --store " + (dir / "t.db").string());
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_NE(cli.output.find("warning: 1 reference(s) in the model files were skipped"), std::string::npos) << cli.output;
}

TEST(InputChecks, AGlbClaimingAHugeChunkIsRefusedBeforeAssimpReadsIt) {
  test::TempDir dir;
  std::string glb = "glTF";
  const std::uint32_t version = 2, length = 200, chunk = 1u << 30;
  glb.append(reinterpret_cast<const char*>(&version), 4);
  glb.append(reinterpret_cast<const char*>(&length), 4);
  glb.append(reinterpret_cast<const char*>(&chunk), 4);
  glb.append("JSON");
  glb.resize(200, ' ');
  test::write_text(dir / "huge.glb", glb);
  const std::string e = read_error(dir / "huge.glb");
  EXPECT_NE(e.find("huge.glb:byte 12: GLB chunk declares 1073741824 bytes but only 180 follow"), std::string::npos) << e;
  std::string lying = glb;
  const std::uint32_t big = 1u << 30;
  std::memcpy(lying.data() + 8, &big, 4);
  test::write_text(dir / "lying.glb", lying);
  EXPECT_NE(read_error(dir / "lying.glb").find("GLB header declares 1073741824 bytes but the file has 200"),
            std::string::npos);
}

}  // namespace
}  // namespace cellbake
