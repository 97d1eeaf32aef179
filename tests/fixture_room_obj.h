// A small OBJ test scene for bake tests: a 12 x 12 x 4 m room with a 4 x 4
// grid of pillars (a few thousand triangles, per-vertex colours), written as
// text so tests can ingest it through the library or the `cellbake` CLI.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "stages/geometry.h"

namespace cellbake::test {

// Appends an axis-aligned box (each face split into n x n quads) to an OBJ stream.
inline void obj_box(std::ostringstream& o, int& next_vertex, Vec3d lo, Vec3d hi, int n = 2) {
  auto quad_grid = [&](Vec3d origin, Vec3d du, Vec3d dv) {
    const int base = next_vertex;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const Vec3d p = origin + du * (double(i) / n) + dv * (double(j) / n);
        o << "v " << p.x << " " << p.y << " " << p.z << " " << (0.3 + 0.1 * (i % 3)) << " 0.5 " << (0.2 + 0.2 * (j % 2))
          << "\n";
        ++next_vertex;
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        o << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
      }
  };
  const Vec3d e = hi - lo;
  quad_grid(lo, {e.x, 0, 0}, {0, e.y, 0});
  quad_grid({lo.x, lo.y, hi.z}, {e.x, 0, 0}, {0, e.y, 0});
  quad_grid(lo, {e.x, 0, 0}, {0, 0, e.z});
  quad_grid({lo.x, hi.y, lo.z}, {e.x, 0, 0}, {0, 0, e.z});
  quad_grid(lo, {0, e.y, 0}, {0, 0, e.z});
  quad_grid({hi.x, lo.y, lo.z}, {0, e.y, 0}, {0, 0, e.z});
}

// The room as OBJ text; `pillars` = false leaves the room empty (a different store).
inline std::string room_obj(bool pillars = true) {
  std::ostringstream o;
  int next = 1;
  obj_box(o, next, {0, 0, 0}, {12, 12, 4}, 8);
  if (pillars)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) obj_box(o, next, {1.5 + 3 * x, 1.5 + 3 * y, 0}, {1.8 + 3 * x, 1.8 + 3 * y, 4}, 3);
  return o.str();
}

// Writes the room as DIR/NAME.obj and ingests it (128-triangle chunks) into
// DIR/NAME.store.db, which it returns.
inline std::filesystem::path ingest_room_store(const std::filesystem::path& dir, const std::string& name = "room",
                                               bool pillars = true) {
  const auto obj = dir / (name + ".obj"), store = dir / (name + ".store.db");
  std::ofstream(obj, std::ios::binary) << room_obj(pillars);
  IngestParams params;
  params.max_chunk_triangles = 128;
  ingest_models({obj}, store, params, tbb_parallel_for());
  return store;
}

// A 12 x 12 x 4 m room (walls split wall_grid x wall_grid) with one pillar
// (x 7..8, y 5..7) and any extra boxes, as OBJ text.
inline std::string pillar_room_obj(int wall_grid = 8, const std::vector<Box3d>& extra = {}) {
  std::ostringstream o;
  int next = 1;
  obj_box(o, next, {0, 0, 0}, {12, 12, 4}, wall_grid);
  obj_box(o, next, {7, 5, 0}, {8, 7, 4}, 4);
  for (const Box3d& b : extra) obj_box(o, next, b.lo, b.hi, 4);
  return o.str();
}

// Writes `obj` as DIR/room.obj, ingests it (128-triangle chunks) into
// DIR/room.store.db and returns a bake configuration for it: 2 m cells over
// `region`, PNG faces of `face_size`, the near budget given, the database
// DIR/cells.db; the rest defaults (several samples per cell).
inline BakeConfig obj_room_bake_config(const std::filesystem::path& dir, const std::string& obj, const Box3d& region,
                                       std::uint64_t near_budget, int face_size) {
  {
    std::ofstream(dir / "room.obj", std::ios::binary) << obj;
  }
  IngestParams ip;
  ip.max_chunk_triangles = 128;
  ingest_models({dir / "room.obj"}, dir / "room.store.db", ip, tbb_parallel_for());
  BakeConfig c;
  c.store = dir / "room.store.db";
  c.regions = {region};
  c.cell_size = 2.0;
  c.near_budget = near_budget;
  c.face_size = face_size;
  c.image_format = "png";
  c.database = dir / "cells.db";
  return c;
}

// run_bake without progress output.
inline BakeSummary bake_quietly(const BakeConfig& config, int threads = 2) {
  BakeOptions options;
  options.threads = threads;
  options.quiet = true;
  return run_bake(config, options);
}

}  // namespace cellbake::test
