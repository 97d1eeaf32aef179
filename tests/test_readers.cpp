// Model readers: per-format round trips on tiny hand-written files with exact
// expected triangles and colours, and bad input that must throw InputError
// naming the file and the place.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/contained_paths.h"
#include "pipeline/readers/model_reader.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

namespace fs = std::filesystem;
using test::TempDir;
using test::write_text;

struct ReadResult {
  ModelInfo info;
  std::vector<Triangle> triangles;
};

ReadResult read_all(const fs::path& file) {
  ReadResult result;
  result.info = read_model(file, [&](const Triangle& t) { result.triangles.push_back(t); });
  return result;
}

// Expects read_model(file) to throw InputError whose message names the file,
// contains `location` ("line 3", "byte 120", ...) and `what`.
void expect_input_error(const fs::path& file, const std::string& location, const std::string& what) {
  try {
    read_model(file, [](const Triangle&) {});
    ADD_FAILURE() << "no InputError for " << file;
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(file.filename().string()), std::string::npos) << message;
    EXPECT_NE(message.find(location), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
}

void write_bytes(const fs::path& file, const std::string& bytes) { write_text(file, bytes); }

void write_gzip(const fs::path& file, const std::string& bytes) {
  gzFile gz = gzopen(file.string().c_str(), "wb");
  ASSERT_NE(gz, nullptr);
  ASSERT_EQ(gzwrite(gz, bytes.data(), static_cast<unsigned>(bytes.size())), static_cast<int>(bytes.size()));
  gzclose(gz);
}

// Appends `value` in little- or big-endian byte order.
template <class T>
void put(std::string& out, T value, bool big_endian) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

constexpr Rgba8 kGrey{200, 200, 200, 255};

// ---------------------------------------------------------------- OBJ

TEST(ObjReader, MaterialQuadAndNegativeIndices) {
  TempDir dir;
  write_text(dir / "colours.mtl",
             "# two materials\n"
             "newmtl red\nKd 1 0 0\nmap_Kd tex/red.png\n"
             "newmtl glass\nKd 0 0 1\nd 0.5\n");
  write_text(dir / "scene.obj",
             "mtllib colours.mtl\n"
             "o quad\n"
             "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
             "usemtl red\n"
             "f 1 2 3 4\n"
             "g second\ns off\n"
             "v 5 5 5\nv 6 5 5\nv 5 6 5\n"
             "usemtl glass\n"
             "f -3 -2 -1\n"
             "usemtl unknown\n"
             "f 1 2 5\n");
  const ReadResult r = read_all(dir / "scene.obj");
  EXPECT_EQ(r.info.format, "obj");
  ASSERT_EQ(r.info.materials.size(), 3u);
  EXPECT_EQ(r.info.materials[0].color, kGrey);
  EXPECT_EQ(r.info.materials[1].name, "red");
  EXPECT_EQ(r.info.materials[1].texture, (dir.path() / "tex/red.png").lexically_normal().string());
  EXPECT_EQ(r.info.materials[2].color, (Rgba8{0, 0, 255, 128}));
  EXPECT_EQ(r.info.triangles_emitted, 4u);
  EXPECT_EQ(r.info.polygons_triangulated, 1u);
  ASSERT_EQ(r.triangles.size(), 4u);

  // The quad becomes the fan (1 2 3), (1 3 4).
  EXPECT_EQ(r.triangles[0].p[0], (Vec3d{0, 0, 0}));
  EXPECT_EQ(r.triangles[0].p[1], (Vec3d{1, 0, 0}));
  EXPECT_EQ(r.triangles[0].p[2], (Vec3d{1, 1, 0}));
  EXPECT_EQ(r.triangles[1].p[0], (Vec3d{0, 0, 0}));
  EXPECT_EQ(r.triangles[1].p[1], (Vec3d{1, 1, 0}));
  EXPECT_EQ(r.triangles[1].p[2], (Vec3d{0, 1, 0}));
  EXPECT_EQ(r.triangles[0].material, 1u);
  EXPECT_EQ(r.triangles[0].color[2], (Rgba8{255, 0, 0, 255}));
  // Negative indices count back from the last vertex defined.
  EXPECT_EQ(r.triangles[2].p[0], (Vec3d{5, 5, 5}));
  EXPECT_EQ(r.triangles[2].p[2], (Vec3d{5, 6, 5}));
  EXPECT_EQ(r.triangles[2].material, 2u);
  EXPECT_EQ(r.triangles[2].color[0], (Rgba8{0, 0, 255, 128}));
  // An unknown material name falls back to the default.
  EXPECT_EQ(r.triangles[3].material, 0u);
  EXPECT_EQ(r.triangles[3].color[1], kGrey);
}

// Texture paths from the exporter's machine ("D:\\maps\\Wood.JPG") or with
// another case than the file: the file of that name beside the model is used.
TEST(ObjReader, TexturePathsFromAnotherMachineFallBackToTheFileBesideTheModel) {
  TempDir dir;
  write_text(dir / "wood.jpg", "");
  write_text(dir / "Stone.png", "");
  fs::create_directories(dir / "tex");
  write_text(dir / "tex" / "exact.png", "");
  write_text(dir / "m.mtl",
             "newmtl a\nmap_Kd D:\\projects\\maps\\Wood.JPG\n"  // drive path, other case
             "newmtl b\nmap_Kd /home/artist/stone.png\n"        // absolute elsewhere, other case
             "newmtl c\nmap_Kd tex\\exact.png\n"                // found as written
             "newmtl d\nmap_Kd C:missing.png\n");               // nowhere: as written
  write_text(dir / "m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
  const ReadResult r = read_all(dir / "m.obj");
  ASSERT_EQ(r.info.materials.size(), 5u);
  EXPECT_EQ(r.info.materials[1].texture, (dir / "wood.jpg").string());
  EXPECT_EQ(r.info.materials[2].texture, (dir / "Stone.png").string());
  EXPECT_EQ(r.info.materials[3].texture, (dir / "tex" / "exact.png").string());
  EXPECT_EQ(r.info.materials[4].texture, (dir / "C:missing.png").string());
  // Never outside the folder: ".." is not a file name to look for.
  EXPECT_EQ(locate_referenced_file(dir / "tex", "../../etc/.."),
            (dir.path().parent_path() / "etc/..").lexically_normal());
}

TEST(ObjReader, VertexColoursTexcoordsAndCornerForms) {
  TempDir dir;
  write_text(dir / "m.mtl", "newmtl half\nKd 0.5 1 1\n");
  write_text(dir / "c.obj",
             "mtllib m.mtl\r\n"
             "v 0 0 0 1 0 0\r\nv 1 0 0 0 1 0\r\nv 0 1 0 0 0 1\r\nv 0 0 1\r\n"
             "vt 0.25 0.75\r\nvt 1 0\r\nvt 0 1\r\n"
             "vn 0 0 1\r\n"
             "f 1/1 2/2 3/3\r\n"
             "f 1//1 2//1 4//1\r\n"
             "usemtl half\r\n"
             "f 1/1/1 2/2/1 4/3/1\r\n");
  const ReadResult r = read_all(dir / "c.obj");
  ASSERT_EQ(r.triangles.size(), 3u);
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{255, 0, 0, 255}));
  EXPECT_EQ(r.triangles[0].color[1], (Rgba8{0, 255, 0, 255}));
  EXPECT_EQ(r.triangles[0].color[2], (Rgba8{0, 0, 255, 255}));
  EXPECT_EQ(r.triangles[0].uv[0], (Uv{0.25f, 0.75f}));
  EXPECT_EQ(r.triangles[0].uv[2], (Uv{0, 1}));
  // A vertex without colour takes the material colour (default grey).
  EXPECT_EQ(r.triangles[1].color[2], kGrey);
  EXPECT_EQ(r.triangles[1].p[2], (Vec3d{0, 0, 1}));
  // Material x vertex colour: 128 = round(0.5 * 255) for Kd 0.5, times red 255.
  EXPECT_EQ(r.triangles[2].color[0], (Rgba8{128, 0, 0, 255}));
  EXPECT_EQ(r.triangles[2].color[1], (Rgba8{0, 255, 0, 255}));
  EXPECT_EQ(r.triangles[2].color[2], (Rgba8{128, 255, 255, 255}));  // no vertex colour: the material colour
  EXPECT_EQ(r.triangles[2].uv[2], (Uv{0, 1}));
}

// Exporters write "v x y z 0 0 0" on every vertex by default: multiplied into
// Kd that would blank the model. Uniform vertex colours give way to the
// material colour (model_reader.h).
TEST(ObjReader, UniformBlackVertexColoursGiveWayToTheMaterial) {
  TempDir dir;
  write_text(dir / "k.mtl", "newmtl red\nKd 1 0 0\n");
  const std::string obj =
      "mtllib k.mtl\n"
      "v 0 0 0 0 0 0\nv 1 0 0 0 0 0\nv 0 1 0 0 0 0\n"
      "f 1 2 3\n"  // under the default material: the vertex colour is all there is
      "usemtl red\n"
      "f 1 2 3\n"
      "v 0 0 1 0 0 0\nv 1 0 1 0 0 0\nv 0 1 1 0 0 0\n"  // more vertices after faces: still all equal
      "f 4 5 6\n";
  write_text(dir / "k.obj", obj);
  write_gzip(dir / "kz.obj.gz", obj);
  for (const char* name : {"k.obj", "kz.obj.gz"}) {
    const ReadResult r = read_all(dir / name);
    ASSERT_EQ(r.triangles.size(), 3u) << name;
    EXPECT_EQ(r.triangles[0].color[0], (Rgba8{0, 0, 0, 255})) << name;
    for (int t = 1; t < 3; ++t)
      for (int i = 0; i < 3; ++i) EXPECT_EQ(r.triangles[t].color[i], (Rgba8{255, 0, 0, 255})) << name << " " << t;
    EXPECT_EQ(r.info.vertex_colours, VertexColourUse::uniform_ignored) << name;
    EXPECT_EQ(r.info.uniform_vertex_colour, (Rgba8{0, 0, 0, 255})) << name;
    EXPECT_EQ(describe_vertex_colours(r.info), "vertex colours: ignored (all equal: 0 0 0), material colours used");
  }
}

// The rule is file-wide: colours that differ only after the first material
// face still vary (the reader looks ahead before emitting that face).
TEST(ObjReader, VaryingVertexColoursStillMultiplyTheMaterial) {
  TempDir dir;
  write_text(dir / "m.mtl", "newmtl half\nKd 0.5 1 1\n");
  write_text(dir / "v.obj",
             "mtllib m.mtl\nusemtl half\n"
             "v 0 0 0 1 1 1\nv 1 0 0 1 1 1\nv 0 1 0 1 1 1\n"
             "f 1 2 3\n"
             "v 0 0 1 0 1 0\nv 1 0 1 0 1 0\nv 0 1 1 1 1 1\n"
             "f 4 5 6\n");
  const ReadResult r = read_all(dir / "v.obj");
  ASSERT_EQ(r.triangles.size(), 2u);
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{128, 255, 255, 255}));  // white x Kd
  EXPECT_EQ(r.triangles[1].color[0], (Rgba8{0, 255, 0, 255}));      // green x Kd
  EXPECT_EQ(r.info.vertex_colours, VertexColourUse::varying);
  EXPECT_NE(describe_vertex_colours(r.info).find("used (they vary"), std::string::npos);
}

TEST(ObjReader, UniformVertexColoursWithoutMaterialsAreKept) {
  TempDir dir;
  write_text(dir / "u.obj", "v 0 0 0 0 0 0\nv 1 0 0 0 0 0\nv 0 1 0 0 0 0\nf 1 2 3\n");
  const ReadResult r = read_all(dir / "u.obj");
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{0, 0, 0, 255}));
  EXPECT_EQ(r.info.vertex_colours, VertexColourUse::uniform_kept);
  EXPECT_NE(describe_vertex_colours(r.info).find("the model is black"), std::string::npos);
  write_text(dir / "none.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(read_all(dir / "none.obj").info.vertex_colours, VertexColourUse::none);
  EXPECT_EQ(describe_vertex_colours(read_all(dir / "none.obj").info), "");
}

TEST(ObjReader, MissingMaterialLibraryFallsBackToDefaultColour) {
  TempDir dir;
  write_text(dir / "a.obj", "mtllib nowhere.mtl\nusemtl steel\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const ReadResult r = read_all(dir / "a.obj");
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.info.materials.size(), 1u);
  EXPECT_EQ(r.triangles[0].color[0], kGrey);
}

TEST(ObjReader, EmptyFileHasNoTriangles) {
  TempDir dir;
  write_text(dir / "empty.obj", "");
  write_text(dir / "comments.obj", "# nothing here\n\n   \n");
  EXPECT_EQ(read_all(dir / "empty.obj").info.triangles_emitted, 0u);
  EXPECT_EQ(read_all(dir / "comments.obj").triangles.size(), 0u);
}

TEST(ObjReader, BadInputNamesFileAndLine) {
  TempDir dir;
  write_text(dir / "nan.obj", "v 0 0 0\nv nan 0 0\n");
  expect_input_error(dir / "nan.obj", "line 2", "non-finite coordinate");
  write_text(dir / "inf.obj", "v 0 0 0\nv 1 -inf 0\n");
  expect_input_error(dir / "inf.obj", "line 2", "non-finite coordinate");
  write_text(dir / "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  expect_input_error(dir / "zero.obj", "line 4", "index 0");
  write_text(dir / "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n");
  expect_input_error(dir / "range.obj", "line 5", "out of range");
  // A face may not refer to a vertex defined after it.
  write_text(dir / "later.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n");
  expect_input_error(dir / "later.obj", "line 3", "out of range");
  write_text(dir / "negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  expect_input_error(dir / "negative.obj", "line 4", "out of range");
  write_text(dir / "garbage.obj", "v 0 0 0\nv 1 0x 0\n");
  expect_input_error(dir / "garbage.obj", "line 2", "malformed");
  write_text(dir / "corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3a\n");
  expect_input_error(dir / "corner.obj", "line 4", "malformed face corner");
  write_text(dir / "texcoord.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n");
  expect_input_error(dir / "texcoord.obj", "line 5", "texture coordinate index 2 out of range");
}

// ---------------------------------------------------------------- PLY

// A PLY with a skipped "material" element (list property) first, 4 coloured
// vertices (uchar colours, an extra ignored property), and faces with an
// extra per-face list before the index list: a quad and a triangle.
std::string tricky_ply(const std::string& format, const std::string& index_type) {
  const bool ascii = format == "ascii";
  const bool big = format == "binary_big_endian";
  std::string out = "ply\nformat " + format + " 1.0\ncomment made by hand\n";
  out += "element material 1\nproperty list uchar float weights\nproperty uchar id\n";
  out += "element vertex 4\nproperty double x\nproperty float y\nproperty int z\nproperty float confidence\n";
  out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out +=
      "element face 2\nproperty list int short tags\nproperty list uchar " + index_type + " vertex_indices\n";
  out += "property uchar flags\nend_header\n";
  const double xs[4] = {0, 10, 10, 0}, ys[4] = {0, 0, 10, 10};
  const int zs[4] = {-1, -1, -1, 5};
  const std::uint8_t colours[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {10, 20, 30}};
  if (ascii) {
    out += "2 0.5 1.5 7\n";
    for (int v = 0; v < 4; ++v)
      out += std::to_string(xs[v]) + " " + std::to_string(ys[v]) + " " + std::to_string(zs[v]) + " 0.9 " +
             std::to_string(colours[v][0]) + " " + std::to_string(colours[v][1]) + " " +
             std::to_string(colours[v][2]) + "\n";
    out += "1 9 4 0 1 2 3 0\n0 3 3 1 0 1\n";
    return out;
  }
  put<std::uint8_t>(out, 2, big);
  put<float>(out, 0.5f, big);
  put<float>(out, 1.5f, big);
  put<std::uint8_t>(out, 7, big);
  for (int v = 0; v < 4; ++v) {
    put<double>(out, xs[v], big);
    put<float>(out, static_cast<float>(ys[v]), big);
    put<std::int32_t>(out, zs[v], big);
    put<float>(out, 0.9f, big);
    for (int c = 0; c < 3; ++c) put<std::uint8_t>(out, colours[v][c], big);
  }
  const auto put_index = [&](int i) {
    if (index_type == "int") put<std::int32_t>(out, i, big);
    if (index_type == "uint") put<std::uint32_t>(out, static_cast<std::uint32_t>(i), big);
    if (index_type == "ushort") put<std::uint16_t>(out, static_cast<std::uint16_t>(i), big);
  };
  put<std::int32_t>(out, 1, big);
  put<std::int16_t>(out, 9, big);
  put<std::uint8_t>(out, 4, big);
  for (int i : {0, 1, 2, 3}) put_index(i);
  put<std::uint8_t>(out, 0, big);
  put<std::int32_t>(out, 0, big);
  put<std::uint8_t>(out, 3, big);
  for (int i : {3, 1, 0}) put_index(i);
  put<std::uint8_t>(out, 1, big);
  return out;
}

void expect_tricky_ply_triangles(const ReadResult& r) {
  EXPECT_EQ(r.info.format, "ply");
  EXPECT_EQ(r.info.triangles_emitted, 3u);
  EXPECT_EQ(r.info.polygons_triangulated, 1u);
  ASSERT_EQ(r.triangles.size(), 3u);
  EXPECT_EQ(r.triangles[0].p[0], (Vec3d{0, 0, -1}));
  EXPECT_EQ(r.triangles[0].p[1], (Vec3d{10, 0, -1}));
  EXPECT_EQ(r.triangles[0].p[2], (Vec3d{10, 10, -1}));
  EXPECT_EQ(r.triangles[1].p[2], (Vec3d{0, 10, 5}));
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{255, 0, 0, 255}));
  EXPECT_EQ(r.triangles[0].color[1], (Rgba8{0, 255, 0, 255}));
  EXPECT_EQ(r.triangles[1].color[1], (Rgba8{0, 0, 255, 255}));
  EXPECT_EQ(r.triangles[2].color[0], (Rgba8{10, 20, 30, 255}));
  EXPECT_EQ(r.triangles[2].p[1], (Vec3d{10, 0, -1}));
  EXPECT_EQ(r.triangles[2].material, 0u);
}

TEST(PlyReader, AsciiWithSkippedElementsAndProperties) {
  TempDir dir;
  write_bytes(dir / "a.ply", tricky_ply("ascii", "int"));
  expect_tricky_ply_triangles(read_all(dir / "a.ply"));
}

TEST(PlyReader, BinaryLittleEndianUintIndices) {
  TempDir dir;
  write_bytes(dir / "le.ply", tricky_ply("binary_little_endian", "uint"));
  expect_tricky_ply_triangles(read_all(dir / "le.ply"));
}

TEST(PlyReader, BinaryBigEndianIntIndices) {
  TempDir dir;
  write_bytes(dir / "be.ply", tricky_ply("binary_big_endian", "int"));
  expect_tricky_ply_triangles(read_all(dir / "be.ply"));
  write_bytes(dir / "be16.ply", tricky_ply("binary_big_endian", "ushort"));
  expect_tricky_ply_triangles(read_all(dir / "be16.ply"));
}

// Old exporters wrote free text in the header without "comment" (Blender
// 2.47: "Created by Blender3D 247 - www.blender.org, source file: ..."): the
// line is read as a comment, with a warning naming it, not a refusal.
TEST(PlyReader, AHeaderLineWithoutAKeywordIsReadAsACommentWithAWarning) {
  TempDir dir;
  write_text(dir / "old.ply",
             "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: 'x.blend'\n"
             "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const ReadResult r = read_all(dir / "old.ply");
  EXPECT_EQ(r.triangles.size(), 1u);
  ASSERT_EQ(r.info.warnings.size(), 1u);
  EXPECT_NE(r.info.warnings[0].find("line 3: header line 'Created by Blender3D 247"), std::string::npos)
      << r.info.warnings[0];
  EXPECT_NE(r.info.warnings[0].find("read as a comment"), std::string::npos) << r.info.warnings[0];
}

TEST(PlyReader, FacesBeforeVerticesFloatColoursAndTexcoords) {
  TempDir dir;
  write_text(dir / "f.ply",
             "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar uint vertex_index\n"
             "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "property float red\nproperty float green\nproperty float blue\nproperty float alpha\n"
             "property float s\nproperty float t\nend_header\n"
             "3 2 1 0\n"
             "0 0 0 1 0.5 0 1 0 0\n1 0 0 0 0 0 0.2 1 0\n0 1 0 1 1 1 1 0 1\n");
  const ReadResult r = read_all(dir / "f.ply");
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.triangles[0].p[0], (Vec3d{0, 1, 0}));
  EXPECT_EQ(r.triangles[0].p[2], (Vec3d{0, 0, 0}));
  EXPECT_EQ(r.triangles[0].color[2], (Rgba8{255, 128, 0, 255}));
  EXPECT_EQ(r.triangles[0].color[1], (Rgba8{0, 0, 0, 51}));
  EXPECT_EQ(r.triangles[0].uv[1], (Uv{1, 0}));
  EXPECT_EQ(r.triangles[0].uv[0], (Uv{0, 1}));
}

// PLY has no material colours: all-black vertex colours are the colour (and
// the reader says so, so the ingest summary can warn).
TEST(PlyReader, UniformBlackVertexColoursAreKeptAndReported) {
  TempDir dir;
  write_text(dir / "b.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "property uchar red\nproperty uchar green\nproperty uchar blue\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0 0 0 0\n1 0 0 0 0 0\n0 1 0 0 0 0\n3 0 1 2\n");
  const ReadResult r = read_all(dir / "b.ply");
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{0, 0, 0, 255}));
  EXPECT_EQ(r.info.vertex_colours, VertexColourUse::uniform_kept);
  EXPECT_NE(describe_vertex_colours(r.info).find("the model is black"), std::string::npos)
      << describe_vertex_colours(r.info);
}

TEST(PlyReader, NoColoursMeansDefaultGrey) {
  TempDir dir;
  write_text(
      dir / "g.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const ReadResult r = read_all(dir / "g.ply");
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.triangles[0].color[0], kGrey);
}

TEST(PlyReader, BadInputNamesFileAndPlace) {
  TempDir dir;
  const std::string binary = tricky_ply("binary_little_endian", "int");
  const std::size_t header_end = binary.find("end_header\n") + 11;
  // Cut inside the second vertex record (material record = 1+8+1 bytes, vertex record = 8+4+4+4+3 bytes).
  const std::size_t second_vertex = header_end + 10 + 23;
  write_bytes(dir / "cut.ply", binary.substr(0, second_vertex + 5));
  expect_input_error(dir / "cut.ply", "byte " + std::to_string(second_vertex), "unexpected end of file");
  // Cut inside the last face's index list.
  write_bytes(dir / "cutface.ply", binary.substr(0, binary.size() - 3));
  expect_input_error(dir / "cutface.ply", "byte", "unexpected end of file");

  std::string out_of_range = binary;
  out_of_range[out_of_range.size() - 1 - 12] = 9;  // first index of the last face: 3 -> 9
  write_bytes(dir / "range.ply", out_of_range);
  expect_input_error(dir / "range.ply", "byte " + std::to_string(binary.size() - 13), "out of range");

  std::string nan_vertex = binary;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(&nan_vertex[second_vertex], &nan, sizeof nan);
  write_bytes(dir / "nan.ply", nan_vertex);
  expect_input_error(dir / "nan.ply", "byte " + std::to_string(second_vertex), "non-finite coordinate");

  write_text(dir / "header.ply", "ply\nformat ascii 1.0\nelement vertex three\nend_header\n");
  expect_input_error(dir / "header.ply", "line 3", "malformed PLY header");
  write_text(dir / "type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n");
  expect_input_error(dir / "type.ply", "line 4", "unknown property type");
  write_text(dir / "magic.ply", "plx\nformat ascii 1.0\nend_header\n");
  expect_input_error(dir / "magic.ply", "line 1", "malformed PLY header");

  const std::string ascii_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  write_text(dir / "ascii_range.ply", ascii_head + "3 0 1 3\n");
  expect_input_error(dir / "ascii_range.ply", "line 13", "out of range");
  write_text(dir / "ascii_count.ply", ascii_head + "-5 0 1 2\n");
  expect_input_error(dir / "ascii_count.ply", "line 13", "negative list count");
  write_text(dir / "ascii_cut.ply", ascii_head + "4 0 1 2\n");
  expect_input_error(dir / "ascii_cut.ply", "line 13", "unexpected end of file");

  // A huge list count in a skipped element ends in a clean truncation error, not an allocation.
  write_bytes(dir / "huge.ply",
              "ply\nformat binary_little_endian 1.0\nelement junk 1\nproperty list uint double v\n"
              "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n\xff\xff\xff\xff");
  expect_input_error(dir / "huge.ply", "byte", "unexpected end of file");
  // So does a vertex count far beyond what the file holds.
  write_bytes(dir / "many.ply",
              "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
              "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
              "end_header\n" +
                  std::string(30, '\0'));
  expect_input_error(dir / "many.ply", "byte", "unexpected end of file");
}

// ---------------------------------------------------------------- OFF

TEST(OffReader, PlainOffWithCommentsAndPolygon) {
  TempDir dir;
  write_text(dir / "a.off",
             "OFF # a square pyramid base\n# comment line\n\n5 2 0\n"
             "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1  # apex\n"
             "4 0 1 2 3\n3 0 1 4 255 0 0\n");
  const ReadResult r = read_all(dir / "a.off");
  EXPECT_EQ(r.info.format, "off");
  EXPECT_EQ(r.info.polygons_triangulated, 1u);
  ASSERT_EQ(r.triangles.size(), 3u);
  EXPECT_EQ(r.triangles[1].p[2], (Vec3d{0, 1, 0}));
  EXPECT_EQ(r.triangles[2].p[2], (Vec3d{0.5, 0.5, 1}));
  EXPECT_EQ(r.triangles[2].color[2], kGrey);
}

TEST(OffReader, CoffIntegerAndFloatColours) {
  TempDir dir;
  write_text(dir / "c.off",
             "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 128\n0 1 0 0 0 255 255\n3 0 1 2\n");
  const ReadResult r = read_all(dir / "c.off");
  ASSERT_EQ(r.triangles.size(), 1u);
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{255, 0, 0, 255}));
  EXPECT_EQ(r.triangles[0].color[1], (Rgba8{0, 255, 0, 128}));
  write_text(dir / "f.off", "COFF 3 1 0\n0 0 0 1.0 0.5 0\n1 0 0 0 0 1.0\n0 1 0 0.2 0.2 0.2\n3 0 1 2\n");
  const ReadResult f = read_all(dir / "f.off");
  ASSERT_EQ(f.triangles.size(), 1u);
  EXPECT_EQ(f.triangles[0].color[0], (Rgba8{255, 128, 0, 255}));
  EXPECT_EQ(f.triangles[0].color[2], (Rgba8{51, 51, 51, 255}));
}

TEST(OffReader, BadInputNamesFileAndLine) {
  TempDir dir;
  write_text(dir / "range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  expect_input_error(dir / "range.off", "line 6", "out of range");
  write_text(dir / "nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
  expect_input_error(dir / "nan.off", "line 4", "non-finite coordinate");
  write_text(dir / "cut.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_input_error(dir / "cut.off", "line 6", "unexpected end of file");
}

// ---------------------------------------------------------------- STL

TEST(StlReader, AsciiFacets) {
  TempDir dir;
  write_text(dir / "a.stl",
             "solid thing\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n"
             "      vertex 0 1 0\n    endloop\n  endfacet\n  facet normal 0 0 1\n    outer loop\n"
             "      vertex 0 0 1e1\n      vertex 1 0 10\n      vertex 0 1 10\n    endloop\n  endfacet\n"
             "endsolid thing\n");
  const ReadResult r = read_all(dir / "a.stl");
  EXPECT_EQ(r.info.format, "stl");
  ASSERT_EQ(r.triangles.size(), 2u);
  EXPECT_EQ(r.triangles[1].p[0], (Vec3d{0, 0, 10}));
  EXPECT_EQ(r.triangles[0].p[2], (Vec3d{0, 1, 0}));
  EXPECT_EQ(r.triangles[0].color[0], kGrey);
}

std::string binary_stl(const std::string& header_text, const std::vector<std::array<float, 9>>& triangles) {
  std::string out = header_text;
  out.resize(80, ' ');
  put<std::uint32_t>(out, static_cast<std::uint32_t>(triangles.size()), false);
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) put<float>(out, 0.0f, false);
    for (float v : t) put<float>(out, v, false);
    put<std::uint16_t>(out, 0, false);
  }
  return out;
}

TEST(StlReader, BinaryEvenWhenHeaderSaysSolid) {
  TempDir dir;
  const std::vector<std::array<float, 9>> triangles = {{0, 0, 0, 1, 0, 0, 0, 1, 0},
                                                       {2, 2, 2, 3, 2, 2, 2, 3, 2.5f}};
  write_bytes(dir / "b.stl", binary_stl("binary export", triangles));
  write_bytes(dir / "s.stl", binary_stl("solid but binary facet", triangles));
  for (const char* name : {"b.stl", "s.stl"}) {
    const ReadResult r = read_all(dir / name);
    ASSERT_EQ(r.triangles.size(), 2u) << name;
    EXPECT_EQ(r.triangles[0].p[1], (Vec3d{1, 0, 0}));
    EXPECT_EQ(r.triangles[1].p[2], (Vec3d{2, 3, 2.5}));
  }
  const std::string full = binary_stl("x", triangles);
  write_bytes(dir / "cut.stl", full.substr(0, full.size() - 1));
  expect_input_error(dir / "cut.stl", "byte 80", "announces 2 triangles");
  write_gzip(dir / "cut.stl.gz", full.substr(0, full.size() - 1));
  expect_input_error(dir / "cut.stl.gz", "byte 134", "unexpected end of file");
}

// ---------------------------------------------------------------- gzip

TEST(GzipInput, ObjAndPlyDecompressOnTheFly) {
  TempDir dir;
  write_gzip(dir / "m.obj.gz", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n");
  const ReadResult obj = read_all(dir / "m.obj.gz");
  EXPECT_EQ(obj.info.format, "obj");
  ASSERT_EQ(obj.triangles.size(), 2u);
  EXPECT_EQ(obj.triangles[1].p[2], (Vec3d{0, 1, 0}));

  write_gzip(dir / "m.PLY.GZ", tricky_ply("binary_big_endian", "uint"));
  expect_tricky_ply_triangles(read_all(dir / "m.PLY.GZ"));

  // STL's binary/ASCII test cannot use the file size under gzip.
  const std::vector<std::array<float, 9>> triangles = {{0, 0, 0, 1, 0, 0, 0, 1, 0}};
  write_gzip(dir / "b.stl.gz", binary_stl("solid exported by a CAD tool", triangles));
  const ReadResult binary = read_all(dir / "b.stl.gz");
  ASSERT_EQ(binary.triangles.size(), 1u);
  EXPECT_EQ(binary.triangles[0].p[2], (Vec3d{0, 1, 0}));
  write_gzip(dir / "a.stl.gz",
             "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
             "vertex 0 1 0\nvertex 0 0 1\nendloop\nendfacet\nendsolid a\n");
  const ReadResult ascii = read_all(dir / "a.stl.gz");
  EXPECT_EQ(ascii.info.polygons_triangulated, 1u);
  ASSERT_EQ(ascii.triangles.size(), 2u);
  EXPECT_EQ(ascii.triangles[1].p[2], (Vec3d{0, 0, 1}));

  // A damaged compressed stream is an error at the decompressed offset reached.
  std::string text;
  for (int i = 0; i < 2000; ++i) text += "v " + std::to_string(i) + " 0 0\n";
  write_gzip(dir / "damaged.obj.gz", text);
  std::ifstream in(dir / "damaged.obj.gz", std::ios::binary);
  std::string compressed((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::size_t i = 20; i < compressed.size() - 8; i += 7)
    compressed[i] = static_cast<char>(compressed[i] ^ 0x5a);
  write_bytes(dir / "damaged.obj.gz", compressed);
  expect_input_error(dir / "damaged.obj.gz", "byte", "gzip error");
  // So is a compressed stream cut short (zlib alone would report a clean end).
  write_gzip(dir / "cut.obj.gz", text);
  std::ifstream cut_in(dir / "cut.obj.gz", std::ios::binary);
  std::string cut((std::istreambuf_iterator<char>(cut_in)), std::istreambuf_iterator<char>());
  write_bytes(dir / "cut.obj.gz", cut.substr(0, cut.size() / 2));
  expect_input_error(dir / "cut.obj.gz", "byte", "truncated");
}

// ---------------------------------------------------------------- assimp

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t chunk = static_cast<std::uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) chunk |= static_cast<std::uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) chunk |= static_cast<std::uint8_t>(bytes[i + 2]);
    out += table[(chunk >> 18) & 63];
    out += table[(chunk >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(chunk >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[chunk & 63] : '=';
  }
  return out;
}

std::string one_triangle_gltf() {
  std::string buffer;
  for (float v : {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f, 3.0f, 0.0f}) put<float>(buffer, v, false);
  for (std::uint16_t i : {0, 1, 2, 0}) put<std::uint16_t>(buffer, i, false);  // 3 indices + padding
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
  "nodes":[{"mesh":0,"translation":[10,0,0]}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
  "materials":[{"name":"red","pbrMetallicRoughness":{"baseColorFactor":[1,0,0,1]}}],
  "buffers":[{"byteLength":44,"uri":"data:application/octet-stream;base64,)" +
         base64(buffer) + R"("}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[2,3,0]},
               {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})";
}

// One triangle with COLOR_0 (float RGBA per vertex) and a red material.
std::string coloured_triangle_gltf(const std::array<float, 12>& colours) {
  std::string buffer;
  for (float v : {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f, 3.0f, 0.0f}) put<float>(buffer, v, false);
  for (float c : colours) put<float>(buffer, c, false);
  for (std::uint16_t i : {0, 1, 2, 0}) put<std::uint16_t>(buffer, i, false);
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0,"COLOR_0":1},"indices":2,"material":0}]}],
  "materials":[{"name":"red","pbrMetallicRoughness":{"baseColorFactor":[1,0,0,1]}}],
  "buffers":[{"byteLength":92,"uri":"data:application/octet-stream;base64,)" +
         base64(buffer) + R"("}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":48},
                 {"buffer":0,"byteOffset":84,"byteLength":6}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[2,3,0]},
               {"bufferView":1,"componentType":5126,"count":3,"type":"VEC4"},
               {"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}]})";
}

TEST(AssimpReader, UniformBlackVertexColoursGiveWayToTheMaterial) {
  TempDir dir;
  write_text(dir / "black.gltf", coloured_triangle_gltf({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}));
  const ReadResult black = read_all(dir / "black.gltf");
  ASSERT_EQ(black.triangles.size(), 1u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(black.triangles[0].color[i], (Rgba8{255, 0, 0, 255})) << i;
  EXPECT_EQ(black.info.vertex_colours, VertexColourUse::uniform_ignored);

  write_text(dir / "varied.gltf", coloured_triangle_gltf({1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 1, 1}));
  const ReadResult varied = read_all(dir / "varied.gltf");
  ASSERT_EQ(varied.triangles.size(), 1u);
  EXPECT_EQ(varied.triangles[0].color[0], (Rgba8{255, 0, 0, 255}));
  EXPECT_EQ(varied.triangles[0].color[1], (Rgba8{0, 0, 0, 255}));
  EXPECT_EQ(varied.info.vertex_colours, VertexColourUse::varying);
}

// Faces assimp drops on import (an index past the vertices) are not lost
// silently: its warning becomes the model's, and the good face is read.
TEST(AssimpReader, FacesAssimpDropsAreReportedInTheWarnings) {
  TempDir dir;
  std::string buffer;
  for (float v : {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f, 3.0f, 0.0f}) put<float>(buffer, v, false);
  for (std::uint16_t i : {0, 1, 2, 0, 1, 7}) put<std::uint16_t>(buffer, i, false);  // vertex 7 does not exist
  write_text(dir / "bad_index.gltf",
             R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
  "buffers":[{"byteLength":48,"uri":"data:application/octet-stream;base64,)" +
                 base64(buffer) + R"("}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":12}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[2,3,0]},
               {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}]})");
  const ReadResult r = read_all(dir / "bad_index.gltf");
  EXPECT_EQ(r.triangles.size(), 1u);
  ASSERT_FALSE(r.info.warnings.empty());
  const auto said = std::find_if(r.info.warnings.begin(), r.info.warnings.end(),
                                 [](const std::string& w) { return w.find("out-of-range") != std::string::npos; });
  ASSERT_NE(said, r.info.warnings.end()) << r.info.warnings.front();
  EXPECT_EQ(said->rfind(" assimp warning: ", 0), 0u) << *said;

  // A clean file says nothing, and a later import does not repeat the old warning.
  write_text(dir / "clean.gltf", one_triangle_gltf());
  EXPECT_TRUE(read_all(dir / "clean.gltf").info.warnings.empty());
}

// A zipped COLLADA file (.zae) is COLLADA: assimp hands it over Y-up, as a
// .dae (a standing figure was baked lying down when z was assumed).
TEST(AssimpReader, ZippedColladaIsYUpLikeCollada) {
  const fs::path zae = "/usr/share/assimp/models/Collada/human.zae";
  if (!fs::exists(zae)) GTEST_SKIP() << zae << " is missing (package assimp-testmodels)";
  const ReadResult r = read_all(zae);
  EXPECT_EQ(r.info.up, "y");
  EXPECT_NE(r.info.up_source.find("COLLADA"), std::string::npos) << r.info.up_source;
  ASSERT_FALSE(r.triangles.empty());
  Box3d b;
  for (const Triangle& t : r.triangles)
    for (const Vec3d& p : t.p) b.expand(p);
  EXPECT_GT(b.hi.y - b.lo.y, b.hi.z - b.lo.z);  // standing along y
}

TEST(AssimpReader, GltfWithEmbeddedBuffer) {
  TempDir dir;
  write_text(dir / "t.gltf", one_triangle_gltf());
  const ReadResult r = read_all(dir / "t.gltf");
  EXPECT_EQ(r.info.format, "assimp:gltf");
  ASSERT_EQ(r.triangles.size(), 1u);
  // The node translation is baked in.
  EXPECT_EQ(r.triangles[0].p[0], (Vec3d{10, 0, 0}));
  EXPECT_EQ(r.triangles[0].p[1], (Vec3d{12, 0, 0}));
  EXPECT_EQ(r.triangles[0].p[2], (Vec3d{10, 3, 0}));
  ASSERT_LT(r.triangles[0].material, r.info.materials.size());
  EXPECT_EQ(r.info.materials[r.triangles[0].material].name, "red");
  EXPECT_EQ(r.triangles[0].color[0], (Rgba8{255, 0, 0, 255}));

  write_gzip(dir / "t.gltf.gz", one_triangle_gltf());
  const ReadResult gz = read_all(dir / "t.gltf.gz");
  ASSERT_EQ(gz.triangles.size(), 1u);
  EXPECT_EQ(gz.triangles[0].p[1], (Vec3d{12, 0, 0}));

  write_text(dir / "broken.gltf", "{\"asset\": ");
  expect_input_error(dir / "broken.gltf", "byte 11", "not valid glTF JSON");  // checked before assimp (gltf_node_graph.h)
}

// Node transforms are composed and applied in double by the reader (assimp's
// own pre-transform works in float): a mesh whose vertices sit millimetres
// from a node placed 1e6 m out keeps them; a mesh placed by two nodes is
// emitted twice, under each; normals follow a non-uniform scale as normals
// do (inverse transpose). (assimp's glTF importer loads only the meshes nodes
// place, so the second mesh here never reaches the reader.)
TEST(AssimpReader, NodeTransformsAreAppliedInDoubleOncePerPlacement) {
  TempDir dir;
  std::string buffer;
  for (float v : {0.001f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f}) put<float>(buffer, v, false);  // 36 B
  const float n = 0.70710678f;
  for (float v : {n, n, 0.0f, n, n, 0.0f, n, n, 0.0f}) put<float>(buffer, v, false);  // normals, 36 B
  for (std::uint16_t i : {0, 1, 2, 0}) put<std::uint16_t>(buffer, i, false);           // 8 B
  write_text(dir / "placed.gltf",
             R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,2]}],
  "nodes":[{"translation":[1000000,0,2000000],"children":[1]},
           {"mesh":0,"scale":[2,1,1]},
           {"mesh":0,"translation":[5,0,0]}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"indices":2}]},
            {"primitives":[{"attributes":{"POSITION":0},"indices":2}]}],
  "buffers":[{"byteLength":80,"uri":"data:application/octet-stream;base64,)" +
                 base64(buffer) + R"("}],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":36},
                 {"buffer":0,"byteOffset":72,"byteLength":6}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
               {"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"},
               {"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}]})");
  const ReadResult r = read_all(dir / "placed.gltf");
  ASSERT_EQ(r.triangles.size(), 2u);
  const Triangle& far = r.triangles[0];  // node 0 -> node 1, depth first
  const Triangle& near = r.triangles[1];  // node 2
  const double x0 = 0.001f;  // the float the file holds
  EXPECT_NEAR(far.p[0].x, 1e6 + 2 * x0, 1e-9);  // float arithmetic would give 1000000.0
  EXPECT_EQ(far.p[0].z, 2e6);
  EXPECT_EQ(far.p[1], (Vec3d{1e6 + 2, 0, 2e6}));
  EXPECT_NEAR(near.p[0].x, 5 + x0, 1e-12);
  EXPECT_EQ(near.p[2], (Vec3d{5, 1, 0}));
  // (1, 1, 0) under scale (2, 1, 1): the inverse transpose gives (0.5, 1, 0), normalised.
  ASSERT_TRUE(far.has_normals);
  EXPECT_NEAR(far.normal[0].x, 0.5 / std::sqrt(1.25), 1e-6);
  EXPECT_NEAR(far.normal[0].y, 1 / std::sqrt(1.25), 1e-6);
  EXPECT_NEAR(near.normal[0].x, n, 1e-6);
  EXPECT_TRUE(r.info.warnings.empty()) << ::testing::PrintToString(r.info.warnings);
}

// Files on which assimp's own pre-transform step crashed the process (an
// assertion on OpenGEX scenes, a segfault on RAW ones) now read.
TEST(AssimpReader, ScenesAssimpsPretransformCrashedOnRead) {
  for (const char* path : {"/usr/share/assimp/models/OpenGEX/camera.ogex", "/usr/share/assimp/models/RAW/WithColor.raw"}) {
    if (!fs::exists(path)) GTEST_SKIP() << path << " is missing (package assimp-testmodels)";
    const ReadResult r = read_all(path);
    EXPECT_FALSE(r.triangles.empty()) << path;
  }
}

// ---------------------------------------------------------------- dispatch

TEST(ReadModel, UnknownExtensionAndMissingFile) {
  TempDir dir;
  write_text(dir / "model.xyz", "1 2 3\n");
  expect_input_error(dir / "model.xyz", "", "unknown model format '.xyz'");
  write_text(dir / "noext", "1 2 3\n");
  expect_input_error(dir / "noext", "", "unknown model format");
  expect_input_error(dir / "absent.obj", "", "no such file");
  expect_input_error(dir / "absent.ply.gz", "", "no such file");
  expect_input_error(dir / "absent.glb", "", "no such file");
}

TEST(ReadModel, ExtensionIsCaseInsensitive) {
  TempDir dir;
  write_text(dir / "UPPER.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(read_all(dir / "UPPER.OBJ").triangles.size(), 1u);
}

}  // namespace
}  // namespace cellbake
