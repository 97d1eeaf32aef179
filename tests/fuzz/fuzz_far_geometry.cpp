// libFuzzer target: a cell's far geometry row checked against the stored
// chunk it names (storage/far_geometry_check.h, `status --check` and merge's
// store-aware validation) and cut out of it as the viewer does
// (chunk_subset), on arbitrary bytes. Input: byte 0 the chunk's triangle
// count (0..255; the store lists levels 1..3 of it, each half the one
// before), byte 1 flags (1: whole; 2: the row's bounds taken from the next 24
// bytes as six int32 / 1024, else those of the triangles named; bits 2..5:
// the row's level, 0..15; 64: that level negated), byte 2 the recorded
// triangle count, then the triangle-list blob. Never throws; a row it passes
// cuts out cleanly with the recorded count and bounds; a row naming a
// triangle past the chunk fails; a level row passes exactly when it is whole,
// without a blob, of a level the store lists with the recorded count.
#include <algorithm>
#include <cstring>
#include <exception>
#include <span>

#include "stages/chunk_subset.h"
#include "stages/encode/encode_triangle_list.h"
#include "storage/far_geometry_check.h"

namespace {

// A chunk of `triangles` separate triangles on a line, origin (10, 20, 30).
cellbake::Chunk stored_chunk(int triangles) {
  cellbake::Chunk c;
  c.id = 1;
  c.origin = {10, 20, 30};
  for (int t = 0; t < triangles; ++t) {
    const float x = float(t);
    for (const cellbake::Vec3f& p :
         {cellbake::Vec3f{x, 0, 0}, cellbake::Vec3f{x + 1, 0, 0}, cellbake::Vec3f{x, 1, 0.5f}}) {
      c.indices.push_back(std::uint32_t(c.positions.size()));
      c.positions.push_back(p);
      c.colors.push_back({200, 100, 50, 255});
      c.bounds.expand(c.origin + cellbake::Vec3d{p.x, p.y, p.z});
    }
    c.materials.push_back(0);
  }
  return c;
}

// The store's levels of a chunk of `triangles` triangles: 1..3, each half the
// one before (none for an empty chunk).
std::vector<cellbake::ChunkLodRef> stored_lods(int triangles) {
  std::vector<cellbake::ChunkLodRef> lods;
  for (int level = 1; level <= 3 && triangles > 0; ++level)
    lods.push_back({level, 0.01 * level, std::uint32_t(std::max(1, triangles >> level))});
  return lods;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  const cellbake::Chunk chunk = stored_chunk(data[0]);
  cellbake::FarGeometryRow row;
  row.chunk_id = 1;
  row.whole = (data[1] & 1) != 0;
  row.triangles = data[2];
  row.level = ((data[1] >> 2) & 15) * ((data[1] & 64) ? -1 : 1);
  const std::vector<cellbake::ChunkLodRef> lods = stored_lods(data[0]);
  std::size_t at = 3;
  std::vector<std::uint32_t> list;
  bool list_ok = false;
  if ((data[1] & 2) && size >= at + 24) {
    std::int32_t v[6];
    std::memcpy(v, data + at, sizeof v);
    row.bounds = {{v[0] / 1024.0, v[1] / 1024.0, v[2] / 1024.0},
                  {v[3] / 1024.0, v[4] / 1024.0, v[5] / 1024.0}};
    at += 24;
  }
  row.geometry.assign(data + at, data + size);
  try {
    list = cellbake::decode_triangle_list(std::span(row.geometry));
    list_ok = true;
  } catch (const std::exception&) {
  }
  const bool in_range = list_ok && (list.empty() || list.back() < chunk.triangle_count());
  if (!(data[1] & 2)) {  // the bounds a sound row has
    if (row.whole || row.level != 0) {
      row.bounds = chunk.bounds;
    } else if (in_range) {
      const cellbake::Chunk part = cellbake::chunk_subset(chunk, list);
      row.bounds = part.bounds;
      row.origin = part.origin;
    }
  }
  const std::string problem = cellbake::far_geometry_problem(row, chunk, lods);  // never throws
  if (row.level != 0) {
    const bool listed = row.level >= 1 && row.level <= int(lods.size()) &&
                        lods[std::size_t(row.level - 1)].triangle_count == row.triangles;
    const bool sound = listed && row.whole && row.geometry.empty();
    if (problem.empty() && !sound) __builtin_trap();                    // a damaged level row passed
    if (!problem.empty() && sound && !(data[1] & 2)) __builtin_trap();  // a sound level row refused
    return 0;
  }
  if (row.whole) {
    if (problem.empty() && (row.triangles != chunk.triangle_count())) __builtin_trap();
    return 0;
  }
  if (!cellbake::is_triangle_list_blob(row.geometry)) return 0;
  if (problem.empty()) {
    // Passed: the viewer's cut succeeds with the recorded count and bounds.
    if (!in_range || list.size() != row.triangles) __builtin_trap();
    const cellbake::Chunk part = cellbake::chunk_subset(chunk, list);
    if (part.triangle_count() != row.triangles) __builtin_trap();
  } else if (in_range && list.size() == row.triangles && !(data[1] & 2)) {
    __builtin_trap();  // a sound row refused
  }
  return 0;
}
