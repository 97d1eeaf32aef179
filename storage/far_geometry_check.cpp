#include "storage/far_geometry_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include "stages/chunk_subset.h"
#include "stages/encode/encode_triangle_list.h"

namespace cellbake {
namespace {

bool close(double a, double b) {
  return a == b || std::fabs(a - b) <= 1e-9 * std::max({1.0, std::fabs(a), std::fabs(b)});
}
bool close(const Vec3d& a, const Vec3d& b) { return close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z); }
bool close(const Box3d& a, const Box3d& b) { return close(a.lo, b.lo) && close(a.hi, b.hi); }

std::string text(const Box3d& b) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g)..(%.9g, %.9g, %.9g)", b.lo.x, b.lo.y, b.lo.z, b.hi.x,
                b.hi.y, b.hi.z);
  return buf;
}

std::string level_list(std::span<const ChunkLodRef> lods) {
  if (lods.empty()) return "none";
  std::string out;
  for (const ChunkLodRef& l : lods)
    out += (out.empty() ? "" : ", ") + std::to_string(l.level) + " (" + std::to_string(l.triangle_count) +
           " triangles)";
  return out;
}

}  // namespace

std::string far_geometry_level_problem(const FarGeometryRow& g) {
  if (g.level == 0) return "";
  const std::string at =
      "far geometry of chunk " + std::to_string(g.chunk_id) + " level " + std::to_string(g.level);
  if (g.level < 0) return at + ": a level is never negative";
  if (g.level > kMaxFarGeometryLevel)
    return at + ": past the highest level a row may name (" + std::to_string(kMaxFarGeometryLevel) + ")";
  if (!g.whole) return at + ": a level row not marked whole (levels are of whole chunks)";
  if (!g.geometry.empty()) return at + ": a level row with a geometry blob";
  return "";
}

std::string far_geometry_problem(const FarGeometryRow& g, const Chunk& stored,
                                 std::span<const ChunkLodRef> lods) {
  const std::string at = "far geometry of chunk " + std::to_string(g.chunk_id);
  try {
    if (std::string problem = far_geometry_level_problem(g); !problem.empty()) return problem;
    if (g.level != 0) {
      const std::string level = at + " level " + std::to_string(g.level);
      const auto it =
          std::find_if(lods.begin(), lods.end(), [&](const ChunkLodRef& l) { return l.level == g.level; });
      if (it == lods.end())
        return level + ": the store holds no such level of the chunk (its levels: " + level_list(lods) + ")";
      if (it->triangle_count != g.triangles)
        return level + ": " + std::to_string(g.triangles) + " triangles recorded, the store's level has " +
               std::to_string(it->triangle_count);
      if (!close(g.bounds, stored.bounds))
        return level + ": bounds " + text(g.bounds) + " are not the store's chunk's " + text(stored.bounds);
      return "";
    }
    if (g.whole) {
      if (g.triangles != stored.triangle_count())
        return at + ": whole, " + std::to_string(g.triangles) +
               " triangles recorded, the store's chunk has " + std::to_string(stored.triangle_count());
      if (!close(g.bounds, stored.bounds))
        return at + ": bounds " + text(g.bounds) + " are not the store's chunk's " + text(stored.bounds);
      return "";
    }
    if (!is_triangle_list_blob(g.geometry)) return "";  // a chunk blob of its own: checked by decoding
    const std::vector<std::uint32_t> list = decode_triangle_list(g.geometry);
    if (list.size() != g.triangles)
      return at + ": " + std::to_string(list.size()) + " triangles, " + std::to_string(g.triangles) +
             " recorded";
    if (!list.empty() && list.back() >= stored.triangle_count())
      return at + ": triangle " + std::to_string(list.back()) + " is past the chunk's " +
             std::to_string(stored.triangle_count()) + " triangles";
    const Chunk part = chunk_subset(stored, list);
    if (!close(g.bounds, part.bounds) || !close(g.origin, part.origin))
      return at + ": bounds " + text(g.bounds) + " are not those of its triangles, " + text(part.bounds);
    return "";
  } catch (const std::exception& e) {
    return at + ": " + e.what();
  }
}

}  // namespace cellbake
