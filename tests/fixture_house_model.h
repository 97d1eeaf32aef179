// A small two-storey house for the first-hour tests (issue #15): 14 x 10 m,
// slabs at 0, 3 and 6 m (each 0.2 m thick, the top one the roof), exterior
// walls, an interior wall, pillars and tables: about 5 500 triangles, enough
// that a suggested near budget leaves a far field. Built as Z-up triangles
// and written as a Z-up OBJ or a Y-up glTF 2.0 (.gltf JSON + .bin beside it,
// (x, y, z) -> (x, z, -y): glTF's convention), so no test needs a model from a
// package.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake::test {

using HouseTriangle = std::array<Vec3d, 3>;

// An axis-aligned box, each face split into n x n quads (two triangles each), outward facing.
inline void add_box(std::vector<HouseTriangle>& out, Vec3d lo, Vec3d hi, int n) {
  const Vec3d e = hi - lo;
  // A face: origin + du * s + dv * t, s, t in [0, 1]; du x dv is its outward normal.
  const auto face = [&](Vec3d origin, Vec3d du, Vec3d dv) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto at = [&](int a, int b) { return origin + du * (double(a) / n) + dv * (double(b) / n); };
        out.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        out.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  };
  const Vec3d x{e.x, 0, 0}, y{0, e.y, 0}, z{0, 0, e.z};
  face(lo, y, x);                  // bottom (-z)
  face({lo.x, lo.y, hi.z}, x, y);  // top (+z)
  face(lo, x, z);                  // front (-y)
  face({lo.x, hi.y, lo.z}, z, x);  // back (+y)
  face(lo, z, y);                  // left (-x)
  face({hi.x, lo.y, lo.z}, y, z);  // right (+x)
}

// The house, Z-up, metres.
inline std::vector<HouseTriangle> house_triangles() {
  std::vector<HouseTriangle> t;
  for (double z : {0.0, 3.0, 6.0})
    add_box(t, {0, 0, z - 0.2}, {14, 10, z}, 8);  // slabs (floor tops at 0, 3, 6)
  add_box(t, {0, 0, 0}, {14, 0.2, 6}, 6);         // exterior walls
  add_box(t, {0, 9.8, 0}, {14, 10, 6}, 6);
  add_box(t, {0, 0.2, 0}, {0.2, 9.8, 6}, 6);
  add_box(t, {13.8, 0.2, 0}, {14, 9.8, 6}, 6);
  add_box(t, {7, 0.2, 0}, {7.2, 6, 2.8}, 4);  // interior wall, ground floor
  for (int k = 0; k < 4; ++k) {
    add_box(t, {2.0 + 3 * k, 7.5, 0}, {2.3 + 3 * k, 7.8, 2.8}, 3);   // pillars
    add_box(t, {2.0 + 3 * k, 2.0, 0}, {3.2 + 3 * k, 2.8, 0.75}, 3);  // tables
    add_box(t, {2.0 + 3 * k, 4.0, 3}, {3.2 + 3 * k, 4.8, 3.75}, 3);  // tables upstairs
  }
  return t;
}

// Z-up OBJ text of the triangles (one vertex per corner).
inline std::string triangles_obj(const std::vector<HouseTriangle>& tris) {
  std::ostringstream o;
  o.precision(9);
  for (const HouseTriangle& t : tris)
    for (const Vec3d& p : t) o << "v " << p.x << " " << p.y << " " << p.z << "\n";
  for (std::size_t i = 0; i < tris.size(); ++i)
    o << "f " << 3 * i + 1 << " " << 3 * i + 2 << " " << 3 * i + 3 << "\n";
  return o.str();
}

// Writes DIR/NAME.gltf and DIR/NAME.bin: the triangles turned Y-up ((x, y, z)
// -> (x, z, -y)) as one unindexed triangle primitive. Returns the .gltf path.
inline std::filesystem::path write_y_up_gltf(const std::filesystem::path& dir, const std::string& name,
                                             const std::vector<HouseTriangle>& tris) {
  std::vector<float> xyz;
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (const HouseTriangle& t : tris)
    for (const Vec3d& p : t) {
      const float v[3] = {float(p.x), float(p.z), float(-p.y)};
      for (int a = 0; a < 3; ++a) {
        xyz.push_back(v[a]);
        lo[a] = std::min(lo[a], v[a]);
        hi[a] = std::max(hi[a], v[a]);
      }
    }
  const std::size_t bytes = xyz.size() * sizeof(float);
  {
    std::ofstream bin(dir / (name + ".bin"), std::ios::binary);
    bin.write(reinterpret_cast<const char*>(xyz.data()), std::streamsize(bytes));
  }
  std::ostringstream j;
  j.precision(9);
  j << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],)"
    << R"( "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 4}]}],)"
    << R"( "buffers": [{"uri": ")" << name << R"(.bin", "byteLength": )" << bytes << "}],"
    << R"( "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": )" << bytes
    << R"(, "target": 34962}],)"
    << R"( "accessors": [{"bufferView": 0, "componentType": 5126, "count": )" << xyz.size() / 3
    << R"(, "type": "VEC3", "min": [)" << lo[0] << ", " << lo[1] << ", " << lo[2] << "], \"max\": [" << hi[0]
    << ", " << hi[1] << ", " << hi[2] << "]}]}\n";
  const auto path = dir / (name + ".gltf");
  std::ofstream(path, std::ios::binary) << j.str();
  return path;
}

}  // namespace cellbake::test
