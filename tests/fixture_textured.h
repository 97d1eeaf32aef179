// Textured test models for the appearance tests: a checkerboard texture whose
// every square has its own colour (so a flipped or transposed mapping shows),
// written as PNG; an OBJ + MTL quad that maps it with map_Kd; and a GLB built
// by hand (JSON chunk + binary chunk: one quad, its texcoords and an embedded
// PNG), so no test needs a model from a package. Texels follow
// stages/texture.h: bottom row first, uv origin at the image's bottom-left.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "stages/encode/encode.h"
#include "stages/geometry.h"

namespace cellbake::test {

// The colour of checker square (i, j): i counts squares along u (left to
// right), j along v (bottom to top), 0..7. Green alternates like a
// checkerboard; red encodes i and blue j, so every square differs.
inline Rgba8 checker_square_colour(int i, int j) {
  return {static_cast<std::uint8_t>(20 + 30 * i), static_cast<std::uint8_t>((i + j) % 2 ? 220 : 30),
          static_cast<std::uint8_t>(20 + 30 * j), 255};
}

// A `squares` x `squares` checkerboard of `square_px` texels per square, bottom row first.
inline std::vector<Rgba8> checker_texels(int squares = 8, int square_px = 8) {
  const int n = squares * square_px;
  std::vector<Rgba8> texels(static_cast<std::size_t>(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) texels[static_cast<std::size_t>(y) * n + x] = checker_square_colour(x / square_px, y / square_px);
  return texels;
}

// PNG bytes of texels stored bottom row first (PNG rows run top first).
inline std::vector<std::uint8_t> png_of_bottom_up(const std::vector<Rgba8>& texels, int width, int height) {
  std::vector<Rgba8> top_down(texels.size());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      top_down[static_cast<std::size_t>(height - 1 - y) * width + x] = texels[static_cast<std::size_t>(y) * width + x];
  ImageEncodeParams png;
  png.format = "png";
  return encode_image(top_down, width, height, png);
}

inline void write_bytes(const std::filesystem::path& file, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline void write_png_bottom_up(const std::filesystem::path& file, const std::vector<Rgba8>& texels, int width,
                                int height) {
  write_bytes(file, png_of_bottom_up(texels, width, height));
}

// A quad with corners c00 (uv 0 0), c10 (uv 1 0), c11 (uv 1 1), c01 (uv 0 1).
struct TexturedQuad {
  Vec3d c00, c10, c11, c01;
  // The world point at texture coordinates (u, v) (bilinear over the corners; exact for a parallelogram).
  Vec3d at(double u, double v) const {
    return c00 * ((1 - u) * (1 - v)) + c10 * (u * (1 - v)) + c11 * (u * v) + c01 * ((1 - u) * v);
  }
};

// The checker quad of the appearance tests: the plane x = 4, u running along
// -y from y = 7 to 5, v along +z from 0.6 to 2.6 (2 m square). Seen from
// (2, 6, 1.6) looking along +x (right = -y, up = +z) u runs left to right and
// v bottom to top.
inline TexturedQuad checker_wall() { return {{4, 7, 0.6}, {4, 5, 0.6}, {4, 5, 2.6}, {4, 7, 2.6}}; }

// OBJ text of `quad` with texcoords, material `material` from `mtllib`.
inline std::string textured_quad_obj(const TexturedQuad& q, const std::string& mtllib, const std::string& material) {
  std::ostringstream o;
  o.precision(17);
  o << "mtllib " << mtllib << "\nusemtl " << material << "\n";
  for (const Vec3d& p : {q.c00, q.c10, q.c11, q.c01}) o << "v " << p.x << " " << p.y << " " << p.z << "\n";
  o << "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  o << "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  return o.str();
}

// Writes DIR/NAME.obj + DIR/NAME.mtl: `quad` under material `material`
// (Kd `kd`, map_Kd `map_kd` when not empty). Returns the OBJ path.
inline std::filesystem::path write_textured_quad_obj(const std::filesystem::path& dir, const std::string& name,
                                                     const TexturedQuad& quad, const std::string& material,
                                                     const std::string& map_kd, const std::string& kd = "1 1 1") {
  {
    std::ofstream mtl(dir / (name + ".mtl"), std::ios::binary);
    mtl << "newmtl " << material << "\nKd " << kd << "\n";
    if (!map_kd.empty()) mtl << "map_Kd " << map_kd << "\n";
  }
  const auto obj = dir / (name + ".obj");
  std::ofstream(obj, std::ios::binary) << textured_quad_obj(quad, name + ".mtl", material);
  return obj;
}

// A binary glTF 2.0 file (GLB) of `quad` (two triangles, TEXCOORD_0, no
// normals) under one material whose baseColorTexture is `png` embedded in the
// binary chunk; the sampler clamps on both axes. glTF's texcoords have their
// origin at the image's top-left, so the file holds (u, 1 - v) for the
// quad's (u, v): imported (assimp flips v), the quad maps the texture like the OBJ.
inline std::vector<std::uint8_t> textured_quad_glb(const TexturedQuad& q, const std::vector<std::uint8_t>& png) {
  std::vector<std::uint8_t> bin;
  const auto put = [&bin](const void* data, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(data);
    bin.insert(bin.end(), b, b + n);
  };
  const Vec3d corners[4] = {q.c00, q.c10, q.c11, q.c01};
  const float uv[4][2] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};  // (u, 1 - v)
  Box3d bounds;
  for (const Vec3d& c : corners) {
    const float p[3] = {static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
    put(p, sizeof p);
    bounds.expand(c);
  }
  put(uv, sizeof uv);  // offset 48
  const std::uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
  put(indices, sizeof indices);  // offset 80, 12 bytes
  const std::size_t image_offset = bin.size();  // 92, 4-aligned
  put(png.data(), png.size());
  while (bin.size() % 4) bin.push_back(0);

  std::ostringstream j;
  j.precision(9);
  j << R"({"asset":{"version":"2.0","generator":"cellbake test"},"scene":0,"scenes":[{"nodes":[0]}],)"
    << R"("nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},)"
    << R"("indices":2,"material":0}]}],)"
    << R"("materials":[{"name":"glb_checker","pbrMetallicRoughness":{"baseColorTexture":{"index":0},)"
    << R"("metallicFactor":0.0,"roughnessFactor":1.0}}],)"
    << R"("textures":[{"source":0,"sampler":0}],)"
    << R"("samplers":[{"magFilter":9729,"minFilter":9987,"wrapS":33071,"wrapT":33071}],)"
    << R"("images":[{"bufferView":3,"mimeType":"image/png"}],)"
    << R"("buffers":[{"byteLength":)" << bin.size() << "}],"
    << R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48,"target":34962},)"
    << R"({"buffer":0,"byteOffset":48,"byteLength":32,"target":34962},)"
    << R"({"buffer":0,"byteOffset":80,"byteLength":12,"target":34963},)"
    << R"({"buffer":0,"byteOffset":)" << image_offset << R"(,"byteLength":)" << png.size() << "}],"
    << R"("accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[)"
    << float(bounds.lo.x) << "," << float(bounds.lo.y) << "," << float(bounds.lo.z) << R"(],"max":[)"
    << float(bounds.hi.x) << "," << float(bounds.hi.y) << "," << float(bounds.hi.z) << "]},"
    << R"({"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"},)"
    << R"({"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}]})";
  std::string json = j.str();
  while (json.size() % 4) json.push_back(' ');

  std::vector<std::uint8_t> glb;
  const auto u32 = [&glb](std::uint32_t v) {
    for (int k = 0; k < 4; ++k) glb.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
  };
  const std::uint32_t total = 12 + 8 + static_cast<std::uint32_t>(json.size()) + 8 + static_cast<std::uint32_t>(bin.size());
  u32(0x46546C67);  // "glTF"
  u32(2);
  u32(total);
  u32(static_cast<std::uint32_t>(json.size()));
  u32(0x4E4F534A);  // "JSON"
  glb.insert(glb.end(), json.begin(), json.end());
  u32(static_cast<std::uint32_t>(bin.size()));
  u32(0x004E4942);  // "BIN\0"
  glb.insert(glb.end(), bin.begin(), bin.end());
  return glb;
}

}  // namespace cellbake::test
