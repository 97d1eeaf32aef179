// Writes the seed corpora of the fuzz targets: `fuzz_seeds DIR` fills
// DIR/<target>/ with small valid inputs made by the project's own encoders
// (chunk blobs, face meshes of both versions, images of every format,
// near-chunk lists) and hand-written model files and configurations
// (`configs/*.toml` are added by scripts/fuzz.sh). Deterministic.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "stages/cube_map.h"
#include "stages/encode/encode.h"
#include "stages/encode/encode_triangle_list.h"
#include "storage/cell_db.h"
#include "storage/chunk_codec.h"
#include "tests/fixture_hostile_models.h"

namespace {

namespace fs = std::filesystem;
using namespace cellbake;

void write(const fs::path& dir, const std::string& name, const void* data, std::size_t size) {
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
}
void write(const fs::path& dir, const std::string& name, const std::string& text) {
  write(dir, name, text.data(), text.size());
}
void write(const fs::path& dir, const std::string& name, const std::vector<std::uint8_t>& bytes) {
  write(dir, name, bytes.data(), bytes.size());
}

template <class T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

Chunk small_chunk(bool uvs, bool normals, bool materials) {
  Chunk c;
  for (int i = 0; i < 6; ++i) {
    c.positions.push_back({float(i % 3), float(i / 3), float(i) * 0.25f});
    c.colors.push_back({std::uint8_t(40 * i), 200, std::uint8_t(255 - 30 * i), 255});
    if (uvs) c.uvs.push_back({float(i) / 5, 1 - float(i) / 5});
    if (normals) c.normals.push_back({0, 0, 1});
  }
  c.indices = {0, 1, 3, 1, 4, 3, 1, 2, 4, 2, 5, 4};
  if (materials) c.materials = {0, 1, 1, 2};
  return c;
}

// An n x n pixel-corner grid on cube face `face` (what the grid coding takes).
FaceMesh ray_grid_mesh(int face, int n) {
  const FaceBasis b = cube_face_basis(face);
  FaceMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double z = 3.0 * (1.0 + 0.4 * std::sin(0.3 * i) * std::cos(0.2 * j));
      const Vec3d d = cube_face_direction(b, 2.0 * i / n - 1, 1 - 2.0 * j / n) * z;
      m.positions.push_back({float(d.x), float(d.y), float(d.z)});
      m.uvs.push_back({float(i) / float(n), float(j) / float(n)});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * (n + 1) + i), c = a + std::uint32_t(n + 1);
      m.indices.insert(m.indices.end(), {a, c, c + 1, a, c + 1, a + 1});
    }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds DIR\n");
    return 2;
  }
  const fs::path root = argv[1];

  for (int k = 0; k < 4; ++k)
    write(root / "fuzz_chunk_codec", "chunk-" + std::to_string(k),
          encode_chunk_blob(small_chunk(k & 1, k & 2, k == 3)));

  write(root / "fuzz_face_mesh", "grid-v2", encode_face_mesh(ray_grid_mesh(2, 6), {2, 6}));
  MeshEncodeParams v1;
  v1.position_bits = 12;
  write(root / "fuzz_face_mesh", "mesh-v1", encode_face_mesh(ray_grid_mesh(0, 5), v1));
  v1.optimize_order = false;
  write(root / "fuzz_face_mesh", "mesh-v1-ordered", encode_face_mesh(ray_grid_mesh(4, 3), v1));

  std::vector<Rgba8> pixels;
  for (int i = 0; i < 8 * 6; ++i)
    pixels.push_back({std::uint8_t(i * 5), std::uint8_t(255 - i), 90, std::uint8_t(128 + i)});
  for (const char* format : {"png", "jpeg", "webp", "avif", "jxl"}) {
    try {
      write(root / "fuzz_image_decode", format, encode_image(pixels, 8, 6, {format, 70}));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "fuzz_seeds: no %s seed: %s\n", format, e.what());
    }
  }

  write(root / "fuzz_near_chunks", "empty", pack_near_chunks({}));
  write(root / "fuzz_near_chunks", "rows",
        pack_near_chunks({{1, 10, true}, {7, 3, false}, {1000000, 4096, true}}));

  write(root / "fuzz_triangle_list", "empty", encode_triangle_list(std::vector<std::uint32_t>{}));
  write(root / "fuzz_triangle_list", "runs", encode_triangle_list(std::vector<std::uint32_t>{0, 1, 2, 7, 9, 10, 4095}));
  {  // fuzz_far_geometry: chunk triangles, flags, recorded count, triangle list
    const auto row = [](std::uint8_t triangles, std::uint8_t flags, std::uint8_t recorded, std::vector<std::uint32_t> list) {
      std::vector<std::uint8_t> bytes = {triangles, flags, recorded};
      const std::vector<std::uint8_t> blob = encode_triangle_list(list);
      bytes.insert(bytes.end(), blob.begin(), blob.end());
      return bytes;
    };
    write(root / "fuzz_far_geometry", "sound", row(40, 0, 4, {0, 1, 7, 39}));
    write(root / "fuzz_far_geometry", "past_end", row(8, 0, 2, {3, 8}));
    write(root / "fuzz_far_geometry", "whole", row(12, 1, 12, {}));
    // Level 2 of a 12-triangle chunk (3 triangles), whole, no blob: flags 1 | 2 << 2.
    write(root / "fuzz_far_geometry", "level", std::vector<std::uint8_t>{12, 1 | 2 << 2, 3});
  }

  const fs::path obj = root / "fuzz_obj_reader";
  write(obj, "triangle.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write(obj, "full.obj",
        "# quad\nmtllib m.mtl\no thing\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl red\ng g\ns 1\n"
        "f 1/1/1 2/2/1 3/3/1 4/4/1\nf -4//1 -3//1 -2//1\nf 1/1 3/3 4/4\nl 1 2\n");
  const fs::path mtl = root / "fuzz_mtl_reader";
  write(mtl, "m.mtl",
        "newmtl red\nKd 1 0 0\nd 0.5\nmap_Kd -s 1 1 1 tex.png\nnewmtl grey\nKd 0.5\nTr 0.25\nd -halo 0.5\n"
        "newmtl spectral\nKd spectral x.rfl\n");

  const fs::path ply = root / "fuzz_ply_reader";
  write(ply, "ascii.ply",
        "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty float x\nproperty float y\nproperty "
        "float z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 "
        "0 1 2\n");
  {
    std::string b =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
        "element face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    for (int i = 0; i < 4; ++i) {
      for (float v : {float(i & 1), float(i >> 1), 0.0f, 0.0f, 0.0f, 1.0f}) put(b, v);
    }
    put<std::uint8_t>(b, 4);
    for (std::uint32_t i : {0u, 1u, 3u, 2u}) put(b, i);
    write(ply, "binary-le.ply", b);
    std::string be =
        "ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uchar int vertex_index\n"
        "element vertex 3\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
    be += std::string("\x03\0\0\0\0\0\0\0\x01\0\0\0\x02", 13);
    for (int i = 0; i < 9; ++i) be += std::string(8, i % 4 == 0 ? '\x3f' : '\0');
    write(ply, "binary-be.ply", be);
  }

  write(root / "fuzz_off_reader", "plain.off",
        "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3 255 0 0\n");
  write(root / "fuzz_off_reader", "coloured.off",
        "COFF\n# comment\n3 1 3\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n");
  write(root / "fuzz_off_reader", "stn.off",
        "STNOFF\n3 1 0\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n");

  write(
      root / "fuzz_stl_reader", "ascii.stl",
      "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
      "endsolid s\n");
  {
    std::string b(80, ' ');
    put<std::uint32_t>(b, 2);
    for (int t = 0; t < 2; ++t) {
      for (float v : {0.0f, 0.0f, 1.0f, 0.0f, 0.0f, float(t), 1.0f, 0.0f, float(t), 0.0f, 1.0f, float(t)})
        put(b, v);
      put<std::uint16_t>(b, 0);
    }
    write(root / "fuzz_stl_reader", "binary.stl", b);
  }

  // The node-tree walkers: small scenes (a chain, a shared child, nesting)
  // and ones past the limits checked before import (deep nesting, a chain
  // too deep, a cycle; glTF children and COLLADA instance_node references;
  // the 2^30-path DAGs are left to HostileModels: their
  // mutants are valid DAGs of up to a million nodes, seconds each).
  write(root / "fuzz_gltf_reader", "chain.gltf", test::gltf_node_chain(3));
  write(root / "fuzz_gltf_reader", "shared.gltf", test::gltf_node_chain(4, 2));
  write(root / "fuzz_gltf_reader", "deep_chain.gltf", test::gltf_node_chain(1100));
  write(root / "fuzz_gltf_reader", "cycle.gltf",
        test::gltf_with_nodes(R"({"children":[1]},{"children":[0],"mesh":0})"));
  write(root / "fuzz_x3d_reader", "nested.x3d", test::x3d_nested_transforms(3));
  write(root / "fuzz_x3d_reader", "deep.x3d", test::x3d_nested_transforms(2100));
  write(root / "fuzz_collada_reader", "nested.dae", test::collada_nested_nodes(3));
  write(root / "fuzz_collada_reader", "deep.dae", test::collada_nested_nodes(2100));
  write(root / "fuzz_collada_reader", "shared.dae", test::collada_instance_nodes(3, 2));
  write(root / "fuzz_collada_reader", "deep_chain.dae", test::collada_instance_nodes(1100));
  write(root / "fuzz_collada_reader", "cycle.dae", test::collada_instance_nodes(2, 1, true));

  write(root / "fuzz_bake_config", "minimal.toml",
        "[input]\nstore = \"model.db\"\n[cells]\nsize = 2.0\nregions = [[0, 0, 0, 4, 4, 2]]\n");
  return 0;
}
