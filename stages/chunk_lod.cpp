#include "stages/chunk_lod.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace cellbake {
namespace {

// The chunk with every vertex that triangles of different materials share
// split into one copy per material (material borders become seams, which
// the simplifier keeps), and each vertex's material.
struct SplitChunk {
  Chunk chunk;
  std::vector<std::uint32_t> vertex_material;
};

SplitChunk split_by_material(const Chunk& chunk) {
  SplitChunk s;
  s.chunk = chunk;
  const std::size_t n = chunk.positions.size();
  s.vertex_material.assign(n, 0);
  if (chunk.materials.empty()) return s;
  std::vector<char> assigned(n, 0);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> copy_of;  // (vertex, material) -> copy
  Chunk& c = s.chunk;
  for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
    const std::uint32_t m = chunk.materials[t];
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& i = c.indices[3 * t + std::size_t(k)];
      if (!assigned[i]) {
        assigned[i] = 1, s.vertex_material[i] = m;
        continue;
      }
      if (s.vertex_material[i] == m) continue;
      const auto [it, added] = copy_of.try_emplace({i, m}, std::uint32_t(c.positions.size()));
      if (added) {
        c.positions.push_back(chunk.positions[i]);
        c.colors.push_back(chunk.colors[i]);
        if (!chunk.uvs.empty()) c.uvs.push_back(chunk.uvs[i]);
        if (!chunk.normals.empty()) c.normals.push_back(chunk.normals[i]);
        s.vertex_material.push_back(m);
      }
      i = it->second;
    }
  }
  return s;
}

// The level made of `indices` (into `from`): only the vertices it uses, in
// first-use order, each triangle's material from its first vertex.
Chunk compact_level(const SplitChunk& from, const std::vector<std::uint32_t>& indices) {
  const Chunk& c = from.chunk;
  Chunk out;
  out.id = c.id;
  out.origin = c.origin;
  out.bounds = c.bounds;
  constexpr std::uint32_t kUnused = ~std::uint32_t{0};
  std::vector<std::uint32_t> remap(c.positions.size(), kUnused);
  out.indices.reserve(indices.size());
  for (std::uint32_t i : indices) {
    if (remap[i] == kUnused) {
      remap[i] = std::uint32_t(out.positions.size());
      out.positions.push_back(c.positions[i]);
      out.colors.push_back(c.colors[i]);
      if (!c.uvs.empty()) out.uvs.push_back(c.uvs[i]);
      if (!c.normals.empty()) out.normals.push_back(c.normals[i]);
    }
    out.indices.push_back(remap[i]);
  }
  if (!c.materials.empty()) {
    out.materials.reserve(indices.size() / 3);
    for (std::size_t t = 0; t < indices.size() / 3; ++t) out.materials.push_back(from.vertex_material[indices[3 * t]]);
  }
  return out;
}

}  // namespace

std::vector<ChunkLod> build_chunk_lods(const Chunk& chunk, const ChunkLodParams& params) {
  std::vector<ChunkLod> levels;
  const std::size_t triangles = chunk.triangle_count();
  if (params.max_levels <= 0 || triangles < 2 * std::max<std::size_t>(params.min_triangles, 1)) return levels;
  for (const Vec3f& p : chunk.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return levels;
  for (std::uint32_t i : chunk.indices)
    if (i >= chunk.positions.size()) return levels;
  const SplitChunk split = split_by_material(chunk);
  const Chunk& c = split.chunk;
  const float* xyz = &c.positions[0].x;
  const float scale = meshopt_simplifyScale(xyz, c.positions.size(), sizeof(Vec3f));
  std::size_t previous = triangles;
  double previous_error = 0;
  bool locked = true;
  std::vector<std::uint32_t> out(c.indices.size());
  for (int level = 1; level <= params.max_levels && previous >= 2 * params.min_triangles; ++level) {
    const auto target = std::size_t(std::llround(double(previous) * params.ratio));
    float relative_error = 0;
    // Any error is allowed: the level is as small as the target asks and
    // records the error it has.
    const std::size_t n = meshopt_simplify(out.data(), c.indices.data(), c.indices.size(), xyz, c.positions.size(),
                                           sizeof(Vec3f), 3 * std::max<std::size_t>(target, 1), 1.0f,
                                           locked ? meshopt_SimplifyLockBorder : 0u, &relative_error);
    const std::size_t kept = n / 3;
    if (kept == 0 || double(kept) > params.min_reduction * double(previous)) {
      if (!locked || !params.unlocked_levels) break;
      locked = false;  // the same level again, borders free to move along themselves
      --level;
      continue;
    }
    // Triangles in vertex-cache order, vertices in first-use order: drawn
    // faster and stored smaller (the chunk codec codes index deltas).
    std::vector<std::uint32_t> ordered(n);
    meshopt_optimizeVertexCache(ordered.data(), out.data(), n, c.positions.size());
    ChunkLod lod;
    lod.chunk = compact_level(split, ordered);
    lod.ref.level = level;
    const double error = double(relative_error) * double(scale) * (locked ? 1.0 : params.unlocked_error_scale);
    lod.ref.error = std::max(previous_error, error);
    lod.ref.triangle_count = std::uint32_t(kept);
    levels.push_back(std::move(lod));
    previous = kept;
    previous_error = lod.ref.error;
  }
  return levels;
}

double box_distance(const Box3d& a, const Box3d& b) {
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, a.lo[k] - b.hi[k], b.lo[k] - a.hi[k]});
    sum += gap * gap;
  }
  return std::sqrt(sum);
}

double allowed_lod_error(double distance, double error_px, int face_size) {
  if (!(distance > 0) || !(error_px > 0) || face_size <= 0) return 0;
  // A pixel at the centre of a 90-degree face spans 2 / face_size of the
  // distance; towards the edges pixels span more, so the centre is the bound.
  return distance * error_px * 2.0 / double(face_size);
}

int choose_lod_level(std::span<const ChunkLodRef> levels, double allowed_error) {
  int best = 0;
  for (const ChunkLodRef& l : levels)
    if (l.error <= allowed_error && l.level > best) best = l.level;
  return best;
}

double median_triangle_width(const Chunk& chunk) {
  std::vector<double> widths;
  widths.reserve(chunk.triangle_count());
  for (std::size_t t = 0; t < chunk.triangle_count(); ++t) {
    const Vec3f& a = chunk.positions[chunk.indices[3 * t]];
    const Vec3f& b = chunk.positions[chunk.indices[3 * t + 1]];
    const Vec3f& c = chunk.positions[chunk.indices[3 * t + 2]];
    const Vec3d ab{double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    const Vec3d ac{double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
    const Vec3d bc{double(c.x) - b.x, double(c.y) - b.y, double(c.z) - b.z};
    const auto length = [](const Vec3d& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); };
    const Vec3d n{ab.y * ac.z - ab.z * ac.y, ab.z * ac.x - ab.x * ac.z, ab.x * ac.y - ab.y * ac.x};
    const double twice_area = length(n);
    const double longest = std::max({length(ab), length(ac), length(bc)});
    if (!std::isfinite(twice_area) || !std::isfinite(longest) || !(longest > 0) || !(twice_area > 0)) continue;
    widths.push_back(twice_area / longest);
  }
  if (widths.empty()) return 0;
  const auto middle = widths.begin() + std::ptrdiff_t(widths.size() / 2);
  std::nth_element(widths.begin(), middle, widths.end());
  return *middle;
}

bool seen_subset_may_miss(double width, double distance, double width_px, int face_size) {
  return width < allowed_lod_error(distance, width_px, face_size);
}

}  // namespace cellbake
