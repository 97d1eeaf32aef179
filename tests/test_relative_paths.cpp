// Relative resource paths resolve against the folder of the file that names
// them, whatever the working directory (issue #41): `cellbake ingest
// sub/m.obj` whose sub/m.mtl says `map_Kd tex/red.png` reads sub/tex/red.png,
// and a glTF in sub/ reads its external buffer and image beside it.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::TempDir;
using test::write_text;

void write_red_png(const std::filesystem::path& file) {
  std::filesystem::create_directories(file.parent_path());
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  const std::vector<std::uint8_t> red{255, 0, 0, 255, 0, 0, 255, 0, 0, 255, 0, 0};
  ASSERT_TRUE(out->open(file.string(), OIIO::ImageSpec(2, 2, 3, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, red.data()));
  ASSERT_TRUE(out->close());
}

// `cellbake ingest MODEL` run in `cwd` (MODEL relative to it); expects one texture stored and no warning.
void expect_texture_found(const std::filesystem::path& cwd, const std::string& model) {
  const test::CommandResult r = test::run_shell("cd '" + cwd.string() + "' && " + CELLBAKE_BINARY +
                                                " ingest " + model + " --store s.db");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 textures stored"), std::string::npos) << model << "\n" << r.output;
  EXPECT_EQ(r.output.find("material colour used"), std::string::npos) << model << "\n" << r.output;
}

TEST(RelativePaths, ObjMtlTexturesResolveAgainstTheMtlFolderFromAnotherWorkingDirectory) {
  TempDir dir;
  write_red_png(dir / "sub" / "tex" / "red.png");
  write_red_png(dir / "sub" / "lib" / "maps" / "red.png");
  write_text(dir / "sub" / "m.mtl", "newmtl m\nKd 1 1 1\nmap_Kd tex/red.png\n");
  write_text(dir / "sub" / "m.obj",
             "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 3/1\n");
  // A library in a subfolder names its texture relative to itself.
  write_text(dir / "sub" / "lib" / "n.mtl", "newmtl n\nKd 1 1 1\nmap_Kd maps/red.png\n");
  write_text(dir / "sub" / "n.obj",
             "mtllib lib/n.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl n\nf 1/1 2/1 3/1\n");
  expect_texture_found(dir.path(), "sub/m.obj");
  expect_texture_found(dir.path(), "sub/n.obj");
  expect_texture_found(dir / "sub", "m.obj");  // as before: run inside the model's folder
}

TEST(RelativePaths, GltfBuffersAndImagesResolveAgainstTheGltfFolderFromAnotherWorkingDirectory) {
  TempDir dir;
  write_red_png(dir / "sub" / "tex" / "red.png");
  // Positions (0,0,0) (1,0,0) (0,1,0), then uvs (0,0) (1,0) (0,1): 60 bytes.
  const float data[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1};
  std::filesystem::create_directories(dir / "sub" / "data");
  std::ofstream(dir / "sub" / "data" / "tri.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(data), sizeof data);
  write_text(
      dir / "sub" / "m.gltf",
      R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"material":0}]}],)"
      R"("materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],)"
      R"("textures":[{"source":0}],"images":[{"uri":"tex/red.png"}],)"
      R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
      R"({"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}],)"
      R"("bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24}],)"
      R"("buffers":[{"byteLength":60,"uri":"data/tri.bin"}]})");
  expect_texture_found(dir.path(), "sub/m.gltf");
}

}  // namespace
}  // namespace cellbake
