// Model input checks (issue #14, items 11-12): binary STL counts, missing
// mtllib warnings, non-regular files, ASCII PLY line numbers, GLB chunk
// lengths checked before assimp allocates them; files a model names read only
// inside its folder unless --allow-outside-paths.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstring>

#include <zlib.h>

#include "pipeline/ingest.h"
#include "pipeline/readers/contained_paths.h"
#include "pipeline/readers/model_reader.h"
#include "tests/fixture_textured.h"
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
  EXPECT_NE(cli.output.find("warning: 1 thing(s) in the model files skipped or read leniently"),
            std::string::npos)
      << cli.output;
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

// ------------------------------------------------------------ path containment

void serial_for(std::size_t n, const std::function<void(std::size_t)>& fn) {
  for (std::size_t i = 0; i < n; ++i) fn(i);
}

TEST(ContainedPaths, InsideMeansTheFolderOrASubfolderAfterLinksAndDotDotAreResolved) {
  test::TempDir dir;
  const auto model = dir / "model";
  std::filesystem::create_directories(model / "sub");
  test::write_text(dir / "secret.txt", "x");
  EXPECT_TRUE(path_inside_folder(model, model / "a.mtl"));  // need not exist
  EXPECT_TRUE(path_inside_folder(model, model / "sub" / ".." / "a.mtl"));
  EXPECT_TRUE(path_inside_folder(model / "", model / "sub/deeper/a.mtl"));
  EXPECT_FALSE(path_inside_folder(model, model / ".." / "secret.txt"));
  EXPECT_FALSE(path_inside_folder(model, "/etc/passwd"));
  EXPECT_FALSE(path_inside_folder(model, model));
  EXPECT_FALSE(path_inside_folder(model, dir / "model-other" / "a.mtl"));  // a prefix of the name is not the folder
  std::filesystem::create_symlink(dir / "secret.txt", model / "link.txt");
  EXPECT_FALSE(path_inside_folder(model, model / "link.txt"));
  std::filesystem::create_directory_symlink(dir.path(), model / "up");
  EXPECT_FALSE(path_inside_folder(model, model / "up" / "secret.txt"));
  EXPECT_FALSE(path_inside_folder(model, model / "up" / "absent.txt"));
}

TEST(ContainedPaths, AnMtllibOutsideTheModelsFolderIsACountedWarningUnlessAllowed) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "model");
  test::write_text(dir / "outside.mtl", "newmtl red\nKd 1 0 0\n");
  test::write_text(dir / "model" / "m.obj", "mtllib ../outside.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  std::filesystem::create_symlink(dir / "outside.mtl", dir / "model" / "link.mtl");
  test::write_text(dir / "model" / "l.obj", "mtllib link.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  for (const char* name : {"m.obj", "l.obj"}) {
    const IngestReport r = ingest_models({dir / "model" / name}, dir / "s.db", IngestParams{}, serial_for);
    ASSERT_EQ(r.input_warnings.size(), 1u) << name;
    EXPECT_EQ(r.input_warnings[0], std::string(name) + ":line 1: mtllib '" +
                                       (name == std::string("m.obj") ? "../outside.mtl" : "link.mtl") +
                                       "': outside the model's folder, not read (--allow-outside-paths allows it); "
                                       "its materials are default grey");
  }
  Rgba8 colour{};
  read_model(dir / "model" / "m.obj", [&](const Triangle& t) { colour = t.color[0]; }, ReadOptions{true});
  EXPECT_EQ(colour, (Rgba8{255, 0, 0, 255}));
  IngestParams allow;
  allow.allow_outside_paths = true;
  EXPECT_TRUE(ingest_models({dir / "model" / "m.obj"}, dir / "s.db", allow, serial_for).input_warnings.empty());

  const auto cli = test::run_cellbake("ingest " + (dir / "model" / "m.obj").string() + " --store " +
                                      (dir / "t.db").string());
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_NE(cli.output.find("warning: 1 thing(s) in the model files skipped or read leniently"),
            std::string::npos)
      << cli.output;
  EXPECT_NE(cli.output.find("m.obj:line 1: mtllib '../outside.mtl': outside the model's folder"), std::string::npos)
      << cli.output;
  const auto allowed = test::run_cellbake("ingest " + (dir / "model" / "m.obj").string() + " --store " +
                                          (dir / "u.db").string() + " --allow-outside-paths");
  EXPECT_EQ(allowed.exit_code, 0) << allowed.output;
  EXPECT_EQ(allowed.output.find("warning"), std::string::npos) << allowed.output;
}

TEST(ContainedPaths, AMapKdOutsideTheModelsFolderIsATextureWarningUnlessAllowed) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "model");
  test::write_png_bottom_up(dir / "outside.png", test::checker_texels(2, 2), 4, 4);
  test::write_png_bottom_up(dir / "model" / "inside.png", test::checker_texels(2, 2), 4, 4);
  const auto outside = test::write_textured_quad_obj(dir / "model", "out", test::checker_wall(), "wall", "../outside.png");
  const IngestReport r = ingest_models({outside}, dir / "s.db", IngestParams{}, serial_for);
  EXPECT_EQ(r.textures, 0u);
  ASSERT_EQ(r.texture_warnings.size(), 1u);
  EXPECT_EQ(r.texture_warnings[0], "out.obj: material 'wall': texture '" + (dir / "outside.png").string() +
                                       "': outside the model's folder, not read (--allow-outside-paths allows it): "
                                       "material colour used");
  IngestParams allow;
  allow.allow_outside_paths = true;
  const IngestReport allowed = ingest_models({outside}, dir / "s.db", allow, serial_for);
  EXPECT_EQ(allowed.textures, 1u);
  EXPECT_TRUE(allowed.texture_warnings.empty());
  EXPECT_NE(allowed.content_hash, r.content_hash);
  const auto inside = test::write_textured_quad_obj(dir / "model", "in", test::checker_wall(), "wall", "inside.png");
  EXPECT_EQ(ingest_models({inside}, dir / "s.db", IngestParams{}, serial_for).textures, 1u);
}

// One triangle whose buffer is the file `uri` (36 bytes of positions, 6 of
// indices), with a material whose base colour texture is the image `image`.
std::string external_buffer_gltf(const std::string& uri, const std::string& image) {
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
  "materials":[{"name":"m","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
  "textures":[{"source":0}],"images":[{"uri":")" + image + R"("}],
  "buffers":[{"byteLength":44,"uri":")" + uri + R"("}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[2,3,0]},
               {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})";
}

std::string triangle_buffer() {
  std::string b;
  for (float v : {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f, 3.0f, 0.0f}) b.append(reinterpret_cast<const char*>(&v), 4);
  for (std::uint16_t i : {0, 1, 2, 0}) b.append(reinterpret_cast<const char*>(&i), 2);
  return b;
}

TEST(ContainedPaths, AGltfBufferOutsideTheModelsFolderIsNeverOpenedUnlessAllowed) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "model" / "data");
  test::write_text(dir / "secret.bin", triangle_buffer());
  test::write_text(dir / "model" / "data" / "inside.bin", triangle_buffer());
  test::write_png_bottom_up(dir / "model" / "inside.png", test::checker_texels(2, 2), 4, 4);
  test::write_png_bottom_up(dir / "outside.png", test::checker_texels(2, 2), 4, 4);

  test::write_text(dir / "model" / "evil.gltf", external_buffer_gltf("../secret.bin", "inside.png"));
  const std::string e = read_error(dir / "model" / "evil.gltf");
  EXPECT_NE(e.find("evil.gltf: needs '"), std::string::npos) << e;
  EXPECT_NE(e.find("secret.bin', outside the model's folder, not read (--allow-outside-paths allows it)"),
            std::string::npos) << e;
  std::size_t triangles = 0;
  read_model(dir / "model" / "evil.gltf", [&](const Triangle&) { ++triangles; }, ReadOptions{true});
  EXPECT_EQ(triangles, 1u);

  std::filesystem::create_symlink(dir / "secret.bin", dir / "model" / "link.bin");
  test::write_text(dir / "model" / "linked.gltf", external_buffer_gltf("link.bin", "inside.png"));
  EXPECT_NE(read_error(dir / "model" / "linked.gltf").find("outside the model's folder"), std::string::npos);

  // Inside (a subfolder) it loads; an image outside is a texture warning.
  test::write_text(dir / "model" / "ok.gltf", external_buffer_gltf("data/inside.bin", "../outside.png"));
  const IngestReport r = ingest_models({dir / "model" / "ok.gltf"}, dir / "s.db", IngestParams{}, serial_for);
  EXPECT_EQ(r.triangles_stored, 1u);
  EXPECT_EQ(r.textures, 0u);
  ASSERT_EQ(r.texture_warnings.size(), 1u);
  EXPECT_NE(r.texture_warnings[0].find("ok.gltf: material 'm': texture '"), std::string::npos) << r.texture_warnings[0];
  EXPECT_NE(r.texture_warnings[0].find("outside.png': outside the model's folder"), std::string::npos);
  test::write_text(dir / "model" / "fine.gltf", external_buffer_gltf("data/inside.bin", "inside.png"));
  const IngestReport fine = ingest_models({dir / "model" / "fine.gltf"}, dir / "s.db", IngestParams{}, serial_for);
  EXPECT_EQ(fine.textures, 1u);
  EXPECT_TRUE(fine.texture_warnings.empty());

  // A compressed glTF resolves its buffer against its own folder, not the working directory.
  const auto gz = dir / "model" / "z.gltf.gz";
  {
    const std::string text = external_buffer_gltf("data/inside.bin", "inside.png");
    gzFile out = gzopen(gz.string().c_str(), "wb");
    ASSERT_NE(out, nullptr);
    gzwrite(out, text.data(), static_cast<unsigned>(text.size()));
    gzclose(out);
  }
  triangles = 0;
  read_model(gz, [&](const Triangle&) { ++triangles; });
  EXPECT_EQ(triangles, 1u);
}

}  // namespace
}  // namespace cellbake
