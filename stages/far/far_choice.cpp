#include "stages/far/far_choice.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

constexpr int kAllTiles = kCubeFaces * kFarTilesPerFace;
constexpr std::uint32_t kFaceTiles = (1u << kFarTilesPerFace) - 1;

// max over the box of w . p
double max_dot(const Vec3d& w, const Box3d& b) {
  double s = 0;
  for (int a = 0; a < 3; ++a) s += std::max(w[a] * b.lo[a], w[a] * b.hi[a]);
  return s;
}

double min_dot(const Vec3d& w, const Box3d& b) { return -max_dot(w * -1.0, b); }

constexpr float kEdge = 1e-6f;  // texture coordinates on a tile border belong to both tiles

struct UvBox {
  float u0 = 1, u1 = 0, v0 = 1, v1 = 0;
};

UvBox uv_box(const FaceMesh& mesh, std::size_t triangle) {
  UvBox b;
  for (int c = 0; c < 3; ++c) {
    const Uv& uv = mesh.uvs[mesh.indices[3 * triangle + std::size_t(c)]];
    b.u0 = std::min(b.u0, uv.u), b.u1 = std::max(b.u1, uv.u);
    b.v0 = std::min(b.v0, uv.v), b.v1 = std::max(b.v1, uv.v);
  }
  return b;
}

// Some p in `box` and e in `eyes` with w . (p - e) >= 0 (a little slack for rounding).
bool plane_reaches(const Vec3d& w, const Box3d& eyes, const Box3d& box) {
  const double hi = max_dot(w, box), lo = min_dot(w, eyes);
  const double scale = std::max({1.0, std::abs(hi), std::abs(lo)});
  return hi - lo >= -1e-9 * scale;
}

}  // namespace

FarChoiceMode parse_far_choice_mode(const std::string& name) {
  if (name == "cheapest") return FarChoiceMode::cheapest;
  if (name == "tdm") return FarChoiceMode::tdm;
  if (name == "geometry") return FarChoiceMode::geometry;
  throw std::invalid_argument("far.choice must be \"cheapest\", \"tdm\" or \"geometry\", not \"" + name + "\"");
}

std::uint32_t tiles_seeing_box(int face, const Box3d& eyes, const Box3d& box) {
  if (eyes.empty() || box.empty()) return 0;
  const FaceBasis b = cube_face_basis(face);
  if (!plane_reaches(b.forward, eyes, box)) return 0;
  // Column c covers s in [s_c, s_c+1], row r covers t in [t_r+1, t_r] (row 0 at the top).
  std::uint32_t columns = 0, rows = 0;
  for (int k = 0; k < kFarTiles; ++k) {
    const double s0 = 2.0 * k / kFarTiles - 1, s1 = 2.0 * (k + 1) / kFarTiles - 1;
    if (plane_reaches(b.right - b.forward * s0, eyes, box) && plane_reaches(b.forward * s1 - b.right, eyes, box))
      columns |= 1u << k;
    const double t1 = 1 - 2.0 * k / kFarTiles, t0 = 1 - 2.0 * (k + 1) / kFarTiles;
    if (plane_reaches(b.up - b.forward * t0, eyes, box) && plane_reaches(b.forward * t1 - b.up, eyes, box))
      rows |= 1u << k;
  }
  std::uint32_t tiles = 0;
  for (int r = 0; r < kFarTiles; ++r)
    for (int c = 0; c < kFarTiles; ++c)
      if ((rows >> r & 1u) && (columns >> c & 1u)) tiles |= 1u << (r * kFarTiles + c);
  return tiles;
}

int triangle_tile(const FaceMesh& mesh, std::size_t triangle) {
  const UvBox b = uv_box(mesh, triangle);
  const int column = std::clamp(int(0.5f * (b.u0 + b.u1) * kFarTiles), 0, kFarTiles - 1);
  const int row = std::clamp(int(0.5f * (b.v0 + b.v1) * kFarTiles), 0, kFarTiles - 1);
  if (b.u0 < float(column) / kFarTiles - kEdge || b.u1 > float(column + 1) / kFarTiles + kEdge) return -1;
  if (b.v0 < float(row) / kFarTiles - kEdge || b.v1 > float(row + 1) / kFarTiles + kEdge) return -1;
  return row * kFarTiles + column;
}

namespace {

// The tiles a triangle's texture-coordinate box reaches (bits as in
// FaceFarChoice::geometry_tiles): one for a triangle within one tile, more
// for one that spans tiles (never fewer than it covers).
std::uint32_t triangle_tile_mask(const FaceMesh& mesh, std::size_t triangle) {
  if (const int tile = triangle_tile(mesh, triangle); tile >= 0) return 1u << tile;
  const UvBox b = uv_box(mesh, triangle);
  const auto first = [](float lo) { return std::clamp(int(std::floor((lo + kEdge) * kFarTiles)), 0, kFarTiles - 1); };
  const auto last = [](float hi, int from) {
    return std::clamp(int(std::ceil((hi - kEdge) * kFarTiles)) - 1, from, kFarTiles - 1);
  };
  const int c0 = first(b.u0), c1 = last(b.u1, c0), r0 = first(b.v0), r1 = last(b.v1, r0);
  std::uint32_t tiles = 0;
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) tiles |= 1u << (r * kFarTiles + c);
  return tiles;
}

}  // namespace

FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor) {
  return choose_far_field(eyes, far_chunks, samples, mode, geometry_factor, FarChoiceMeshSource{});
}

FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                           const FarChoiceMeshSource& mesh_source) {
  return choose_far_field(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, FarChoiceBoundSource{});
}

namespace {

FarChoice choose_with_levels(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                             std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                             const FarChoiceMeshSource& mesh_source, const FarChoiceBoundSource& bound_source,
                             std::span<const FarLodChoice> lods);

}  // namespace

FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                           const FarChoiceMeshSource& mesh_source, const FarChoiceBoundSource& bound_source,
                           std::span<const FarLodChoice> lods) {
  if (lods.empty())
    return choose_with_levels(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, bound_source, lods);
  if (lods.size() != far_chunks.size())
    throw std::invalid_argument("choose_far_field: " + std::to_string(lods.size()) + " level choices for " +
                                std::to_string(far_chunks.size()) + " far chunks");
  // First the levels that may replace exact triangles; a chunk this choice
  // draws keeps what it drew (exact triangles where they were affordable),
  // and the other levels only bring in chunks it could not pay for.
  std::vector<FarLodChoice> levels(lods.begin(), lods.end());
  bool deferred = false;
  for (FarLodChoice& l : levels)
    if (l.level > 0 && !l.replaces_exact) l = {}, deferred = true;
  const FarChoice first =
      choose_with_levels(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, bound_source, levels);
  if (!deferred) return first;
  std::vector<char> drawn(far_chunks.size(), 0);
  for (const FarPiece& p : first.pieces) {
    const auto it = std::lower_bound(far_chunks.begin(), far_chunks.end(), p.chunk.id,
                                     [](const ChunkRef& c, std::int64_t v) { return c.id < v; });
    if (it != far_chunks.end() && it->id == p.chunk.id) drawn[std::size_t(it - far_chunks.begin())] = 1;
  }
  bool joined = false;
  for (std::size_t i = 0; i < lods.size(); ++i)
    if (lods[i].level > 0 && !lods[i].replaces_exact && !drawn[i]) levels[i] = lods[i], joined = true;
  if (!joined) return first;
  return choose_with_levels(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, bound_source, levels);
}

namespace {

FarChoice choose_with_levels(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                             std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                             const FarChoiceMeshSource& mesh_source, const FarChoiceBoundSource& bound_source,
                             std::span<const FarLodChoice> lods) {
  FarChoice out;
  if (!lods.empty() && lods.size() != far_chunks.size())
    throw std::invalid_argument("choose_far_field: " + std::to_string(lods.size()) + " level choices for " +
                                std::to_string(far_chunks.size()) + " far chunks");
  const auto level_of = [&](std::size_t i) { return lods.empty() ? FarLodChoice{} : lods[i]; };
  std::vector<char> use_level(far_chunks.size(), 0);
  // What each tile would drop: its depth-mesh triangles, counted from the
  // meshes known so far. Triangles spanning tiles are dropped only when all
  // the tiles they reach take geometry (counted in the gain of the group
  // that completes them, not in any one tile's).
  std::vector<std::uint64_t> removable(kAllTiles, 0);
  // Per face: how many spanning triangles reach each set of tiles (sorted by
  // tile set), and the union of those sets.
  std::array<std::vector<std::pair<std::uint32_t, std::uint64_t>>, kCubeFaces> spanning;
  std::array<std::uint32_t, kCubeFaces> spanned_tiles{};
  std::vector<std::array<char, kCubeFaces>> known(samples.size());
  std::array<int, kCubeFaces> missing{};  // per face: samples whose mesh is not known yet
  const auto count_mesh = [&](int f, const FaceMesh& m) {
    auto& sets = spanning[std::size_t(f)];
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const int tile = triangle_tile(m, t);
      if (tile >= 0) {
        ++removable[std::size_t(f * kFarTilesPerFace + tile)];
        continue;
      }
      const std::uint32_t tiles = triangle_tile_mask(m, t);
      spanned_tiles[std::size_t(f)] |= tiles;
      const auto it = std::lower_bound(sets.begin(), sets.end(), std::make_pair(tiles, std::uint64_t{0}));
      if (it != sets.end() && it->first == tiles)
        ++it->second;
      else
        sets.insert(it, {tiles, 1});
    }
  };
  for (std::size_t i = 0; i < samples.size(); ++i)
    for (int f = 0; f < kCubeFaces; ++f) {
      known[i][std::size_t(f)] = samples[i].meshes[std::size_t(f)] != nullptr || !mesh_source;
      if (samples[i].meshes[std::size_t(f)]) count_mesh(f, *samples[i].meshes[std::size_t(f)]);
      missing[std::size_t(f)] += !known[i][std::size_t(f)];
    }
  std::vector<char> geometry(kAllTiles, 0);
  // Face f's tiles (bits as in FaceFarChoice::geometry_tiles) already taken,
  // and those of the group first..first+count-1 not taken yet.
  const auto face_tiles = [&](int f, int first, int count) {
    std::uint32_t taken = 0, open = 0;
    for (int b = 0; b < kFarTilesPerFace; ++b) {
      const int k = f * kFarTilesPerFace + b;
      if (geometry[std::size_t(k)])
        taken |= 1u << b;
      else if (k >= first && k < first + count)
        open |= 1u << b;
    }
    return std::make_pair(taken, open);
  };
  // Lower bounds on the triangles of meshes not known yet (bounded: asked for).
  std::vector<std::array<std::uint64_t, kCubeFaces>> bound(samples.size());
  std::vector<std::array<char, kCubeFaces>> bounded(samples.size());
  std::uint64_t learned_triangles = 0, learned_faces = 0;  // over the meshes and bounds learned (a mesh replaces its bound)
  const auto bound_only = [&](std::size_t i, int f) { return bounded[i][std::size_t(f)] && !known[i][std::size_t(f)]; };
  // Learns about a missing mesh of a face with a tile in first..first+count-1
  // not taken yet: the bound of one whose face the group covers wholly open
  // (there every triangle counts, so the bound does too), else the mesh;
  // each time the largest guess, then the first in sample and face order.
  // False when no mesh is missing there.
  const auto learn_one = [&](int first, int count, bool meshes_only) {
    std::size_t best_sample = 0;
    int best_face = -1;
    bool best_bound = false;
    for (std::size_t i = 0; i < samples.size(); ++i)
      for (int f = first / kFarTilesPerFace; f <= (first + count - 1) / kFarTilesPerFace; ++f) {
        if (known[i][std::size_t(f)]) continue;
        const auto [taken, open] = face_tiles(f, first, count);
        if (open == 0) continue;
        const bool by_bound =
            bound_source && !meshes_only && !bounded[i][std::size_t(f)] && taken == 0 && open == kFaceTiles;
        if (best_face >= 0 && (by_bound != best_bound ? best_bound : samples[i].mesh_guess[std::size_t(f)] <=
                                                                          samples[best_sample].mesh_guess[std::size_t(best_face)]))
          continue;
        best_sample = i, best_face = f, best_bound = by_bound;
      }
    if (best_face < 0) return false;
    const std::size_t f = std::size_t(best_face);
    if (best_bound) {
      bounded[best_sample][f] = 1;
      bound[best_sample][f] = bound_source(best_sample, best_face);
      learned_triangles += bound[best_sample][f], ++learned_faces;
      return true;
    }
    known[best_sample][f] = 1;
    --missing[f];
    const FaceMesh& mesh = mesh_source(best_sample, best_face);
    count_mesh(best_face, mesh);
    if (bounded[best_sample][f])
      learned_triangles = learned_triangles - bound[best_sample][f] + mesh.triangle_count();
    else
      learned_triangles += mesh.triangle_count(), ++learned_faces;
    return true;
  };
  // Faces with a tile in the group not taken yet whose mesh is neither known
  // nor bounded.
  const auto unlearned_faces = [&](int first, int count) {
    std::uint64_t n = 0;
    for (std::size_t i = 0; i < samples.size(); ++i)
      for (int f = first / kFarTilesPerFace; f <= (first + count - 1) / kFarTilesPerFace; ++f)
        n += !known[i][std::size_t(f)] && !bounded[i][std::size_t(f)] && face_tiles(f, first, count).second != 0;
    return n;
  };

  // What each tile would need: elements (a whole chunk, or one triangle of a
  // chunk) with their triangle counts.
  struct Element {
    std::uint32_t chunk;
    std::uint32_t triangle;  // kWhole: the whole chunk
    std::uint64_t weight;
  };
  constexpr std::uint32_t kWhole = ~std::uint32_t{0};
  std::vector<Element> elements;
  std::vector<std::vector<std::uint32_t>> tile_elements(kAllTiles);
  const auto add = [&](int face, std::uint32_t tiles, std::uint32_t element) {
    for (int k = 0; k < kFarTilesPerFace; ++k)
      if (tiles >> k & 1u) tile_elements[std::size_t(face * kFarTilesPerFace + k)].push_back(element);
  };
  if (samples.empty()) {
    mode = FarChoiceMode::geometry;
    for (std::size_t i = 0; i < far_chunks.size(); ++i) {
      const FarLodChoice l = level_of(i);
      use_level[i] = l.level > 0 && l.triangles < far_chunks[i].triangle_count;
      elements.push_back({std::uint32_t(i), kWhole, use_level[i] ? l.triangles : far_chunks[i].triangle_count});
      for (int f = 0; f < kCubeFaces; ++f)
        add(f, tiles_seeing_box(f, eyes, far_chunks[i].bounds), std::uint32_t(elements.size() - 1));
    }
  } else {
    // Per far chunk seen: whole (any sample saw it whole) or its triangles;
    // element ids through a dense per-triangle table of the chunks seen.
    const auto index_of = [&](std::int64_t id) -> std::int64_t {
      const auto it = std::lower_bound(far_chunks.begin(), far_chunks.end(), id,
                                       [](const ChunkRef& c, std::int64_t v) { return c.id < v; });
      return it != far_chunks.end() && it->id == id ? it - far_chunks.begin() : -1;
    };
    std::vector<char> whole(far_chunks.size(), 0), seen(far_chunks.size(), 0);
    for (const FarChoiceSample& sample : samples)
      for (const auto* list : sample.seen)
        if (list)
          for (const SeenChunk& c : *list)
            if (const std::int64_t i = index_of(c.id); i >= 0) {
              seen[std::size_t(i)] = 1;
              if (c.whole()) whole[std::size_t(i)] = 1;
            }
    std::vector<std::size_t> offset(far_chunks.size() + 1, 0);
    for (std::size_t i = 0; i < far_chunks.size(); ++i)
      offset[i + 1] = offset[i] + (seen[i] && !whole[i] ? far_chunks[i].triangle_count : 0);
    std::vector<std::uint32_t> element_of(offset.back(), kWhole);
    if (!lods.empty()) {
      // A chunk's level replaces what was seen of it when it costs fewer triangles.
      std::vector<std::uint64_t> seen_count(far_chunks.size(), 0);
      for (std::size_t i = 0; i < far_chunks.size(); ++i)
        if (whole[i]) seen_count[i] = far_chunks[i].triangle_count;
      for (const FarChoiceSample& sample : samples)
        for (const auto* list : sample.seen)
          if (list)
            for (const SeenChunk& c : *list)
              if (const std::int64_t i = index_of(c.id); i >= 0 && !whole[std::size_t(i)])
                for (std::uint32_t t : c.triangles)
                  if (t < far_chunks[std::size_t(i)].triangle_count && element_of[offset[std::size_t(i)] + t] == kWhole)
                    element_of[offset[std::size_t(i)] + t] = 0, ++seen_count[std::size_t(i)];
      std::fill(element_of.begin(), element_of.end(), kWhole);
      for (std::size_t i = 0; i < far_chunks.size(); ++i) {
        const FarLodChoice l = level_of(i);
        use_level[i] = seen[i] && l.level > 0 && l.triangles < seen_count[i];
        if (use_level[i]) whole[i] = 1;
      }
    }
    std::vector<std::uint32_t> whole_element(far_chunks.size(), kWhole);
    for (const FarChoiceSample& sample : samples)
      for (int f = 0; f < kCubeFaces; ++f) {
        if (!sample.seen[std::size_t(f)]) continue;
        for (const SeenChunk& c : *sample.seen[std::size_t(f)]) {
          const std::int64_t i = index_of(c.id);
          if (i < 0) continue;
          const std::size_t ci = std::size_t(i);
          if (whole[ci]) {
            if (whole_element[ci] == kWhole) {
              whole_element[ci] = std::uint32_t(elements.size());
              elements.push_back(
                  {std::uint32_t(ci), kWhole, use_level[ci] ? level_of(ci).triangles : far_chunks[ci].triangle_count});
            }
            add(f, c.tiles, whole_element[ci]);
            continue;
          }
          for (std::size_t k = 0; k < c.triangles.size(); ++k) {
            const std::uint32_t t = c.triangles[k];
            if (t >= far_chunks[ci].triangle_count) continue;  // not this chunk's: ignore
            std::uint32_t& e = element_of[offset[ci] + t];
            if (e == kWhole) {
              e = std::uint32_t(elements.size());
              elements.push_back({std::uint32_t(ci), t, 1});
            }
            add(f, c.triangle_tiles[k], e);
          }
        }
      }
    for (auto& list : tile_elements) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
  }

  std::vector<char> chosen(elements.size(), 0);
  std::vector<std::uint32_t> stamp_of(elements.size(), 0);
  std::uint32_t stamp = 0;
  // Takes geometry for the group's tiles not taken yet when it pays. The
  // gain known so far is a lower bound: it decides "yes" at once, while a
  // "no" first learns the group's missing meshes one by one.
  const auto try_group = [&](int first, int count, bool force) {
    ++stamp;
    std::uint64_t extra = 0;
    bool any = false;
    for (int k = first; k < first + count; ++k) {
      if (geometry[std::size_t(k)]) continue;
      any = true;
      for (std::uint32_t e : tile_elements[std::size_t(k)])
        if (!chosen[e] && stamp_of[e] != stamp) stamp_of[e] = stamp, extra += elements[e].weight;
    }
    if (!any) return false;
    // The depth-mesh triangles taking the group drops: those within its open
    // tiles, and those spanning tiles that all draw geometry once it is taken.
    const auto gain = [&] {
      std::uint64_t g = 0;
      for (int k = first; k < first + count; ++k)
        if (!geometry[std::size_t(k)]) g += removable[std::size_t(k)];
      for (int f = first / kFarTilesPerFace; f <= (first + count - 1) / kFarTilesPerFace; ++f) {
        const auto [taken, open] = face_tiles(f, first, count);
        if (open == 0) continue;
        for (const auto& [tiles, n] : spanning[std::size_t(f)])
          if ((tiles & ~(taken | open)) == 0 && (tiles & open) != 0) g += n;
        if (taken == 0 && open == kFaceTiles)  // the whole face goes: so do the bounded meshes' triangles
          for (std::size_t i = 0; i < samples.size(); ++i)
            if (bound_only(i, f)) g += bound[i][std::size_t(f)];
      }
      return g;
    };
    const auto pays = [&](std::uint64_t g) {
      return extra + g > 0 && (force || double(extra) <= geometry_factor * double(g));
    };
    // Bounds are asked for while they may decide: while the faces not
    // learned yet, at the mean size of those learned, could make the group
    // pay. Otherwise meshes are (the decision is exact either way; this only
    // saves holding bounded faces that will be meshed anyway).
    if (!(force && extra > 0))
      for (std::uint64_t g = gain(); !pays(g); g = gain()) {
        const bool promising =
            learned_faces == 0 || pays(g + unlearned_faces(first, count) * learned_triangles / learned_faces);
        if (!learn_one(first, count, !promising)) return false;
      }
    for (int k = first; k < first + count; ++k) {
      if (geometry[std::size_t(k)]) continue;
      if (tile_elements[std::size_t(k)].empty() && removable[std::size_t(k)] == 0 &&
          missing[std::size_t(k / kFarTilesPerFace)] == 0 &&
          !(spanned_tiles[std::size_t(k / kFarTilesPerFace)] >> (k % kFarTilesPerFace) & 1u))
        continue;
      geometry[std::size_t(k)] = 1;
      for (std::uint32_t e : tile_elements[std::size_t(k)]) chosen[e] = 1;
    }
    return true;
  };
  if (mode == FarChoiceMode::geometry) {
    try_group(0, kAllTiles, true);
  } else if (mode == FarChoiceMode::cheapest) {
    for (bool changed = true; changed;) {
      changed = try_group(0, kAllTiles, false);
      for (int f = 0; f < kCubeFaces; ++f) changed = try_group(f * kFarTilesPerFace, kFarTilesPerFace, false) || changed;
      for (int k = 0; k < kAllTiles; ++k) changed = try_group(k, 1, false) || changed;
    }
  }

  // A face keeping depth meshes anywhere needs all its meshes (tdm mode, or
  // tiles no geometry pays for).
  for (int f = 0; f < kCubeFaces; ++f)
    for (int k = 0; k < kFarTilesPerFace && missing[std::size_t(f)] > 0; ++k)
      if (!geometry[std::size_t(f * kFarTilesPerFace + k)])
        while (learn_one(f * kFarTilesPerFace, kFarTilesPerFace, true)) {
        }

  for (int f = 0; f < kCubeFaces; ++f) {
    FaceFarChoice& face = out.faces[std::size_t(f)];
    ++stamp;
    for (int k = 0; k < kFarTilesPerFace; ++k) {
      const std::size_t tile = std::size_t(f * kFarTilesPerFace + k);
      if (!geometry[tile]) {
        face.tdm_triangles += removable[tile];
        continue;
      }
      face.geometry_tiles |= 1u << k;
      face.replaced_triangles += removable[tile];
      for (std::uint32_t e : tile_elements[tile])
        if (stamp_of[e] != stamp) stamp_of[e] = stamp, face.geometry_triangles += elements[e].weight;
    }
    for (const auto& [tiles, n] : spanning[std::size_t(f)])
      ((tiles & ~face.geometry_tiles) == 0 ? face.replaced_triangles : face.tdm_triangles) += n;
    for (std::size_t i = 0; i < samples.size(); ++i)  // meshes never learned: their faces are all geometry
      if (bound_only(i, f)) face.replaced_triangles += bound[i][std::size_t(f)];
  }
  // Chosen elements grouped into pieces by chunk (chunks ascend by id).
  std::vector<std::uint32_t> order;
  for (std::uint32_t e = 0; e < elements.size(); ++e)
    if (chosen[e]) order.push_back(e);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return elements[a].chunk != elements[b].chunk ? elements[a].chunk < elements[b].chunk
                                                  : elements[a].triangle < elements[b].triangle;
  });
  for (std::uint32_t e : order) {
    const Element& el = elements[e];
    if (out.pieces.empty() || out.pieces.back().chunk.id != far_chunks[el.chunk].id) {
      out.pieces.push_back({far_chunks[el.chunk], {}});
      if (use_level[el.chunk]) {
        out.pieces.back().level = level_of(el.chunk).level;
        out.pieces.back().level_triangles = level_of(el.chunk).triangles;
      }
    }
    if (el.triangle != kWhole) out.pieces.back().triangles.push_back(el.triangle);
  }
  for (const FarPiece& p : out.pieces) out.geometry_triangles += p.triangle_count();
  return out;
}

}  // namespace

VertexTriangles vertex_triangles(const Chunk& chunk) {
  VertexTriangles a;
  a.offsets.assign(chunk.positions.size() + 1, 0);
  for (std::uint32_t i : chunk.indices)
    if (i < chunk.positions.size()) ++a.offsets[i + 1];
  for (std::size_t v = 1; v < a.offsets.size(); ++v) a.offsets[v] += a.offsets[v - 1];
  a.triangles.resize(a.offsets.back());
  std::vector<std::uint32_t> next(a.offsets.begin(), a.offsets.end() - 1);
  for (std::size_t k = 0; k < chunk.indices.size(); ++k)
    if (const std::uint32_t i = chunk.indices[k]; i < chunk.positions.size())
      a.triangles[next[i]++] = std::uint32_t(k / 3);
  return a;
}

void grow_seen_triangles(SeenChunk& seen, const Chunk& chunk, const VertexTriangles& adjacency, int rings,
                         std::vector<std::uint16_t>& scratch) {
  if (seen.whole() || rings <= 0) return;
  const std::size_t n = chunk.triangle_count();
  // scratch is zero on entry and on return; only the triangles touched here
  // are set and cleared, so a small seen set in a large chunk costs its own
  // size, not the chunk's.
  if (scratch.size() < n) scratch.resize(n, 0);
  std::vector<std::uint32_t> touched, frontier;
  for (std::size_t k = 0; k < seen.triangles.size(); ++k)
    if (const std::uint32_t t = seen.triangles[k]; t < n) {
      const std::uint16_t before = scratch[t];
      scratch[t] |= seen.triangle_tiles[k];
      if (before == 0 && scratch[t] != 0) touched.push_back(t);
      frontier.push_back(t);
    }
  for (int ring = 0; ring < rings && !frontier.empty(); ++ring) {
    std::vector<std::uint32_t> added;
    for (std::uint32_t t : frontier) {
      const std::uint16_t tiles = scratch[t];
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = chunk.indices[3 * std::size_t(t) + std::size_t(c)];
        if (v + 1 >= adjacency.offsets.size()) continue;
        for (std::uint32_t k = adjacency.offsets[v]; k < adjacency.offsets[v + 1]; ++k) {
          const std::uint32_t u = adjacency.triangles[k];
          if ((scratch[u] | tiles) == scratch[u]) continue;
          if (scratch[u] == 0) added.push_back(u), touched.push_back(u);
          scratch[u] |= tiles;
        }
      }
    }
    frontier = std::move(added);
  }
  std::sort(touched.begin(), touched.end());
  seen.triangles.clear();
  seen.triangle_tiles.clear();
  seen.tiles = 0;
  for (const std::uint32_t t : touched) {
    seen.triangles.push_back(t);
    seen.triangle_tiles.push_back(scratch[t]);
    seen.tiles |= scratch[t];
    scratch[t] = 0;
  }
}

std::size_t drop_geometry_tiles(FaceMesh& mesh, std::uint32_t geometry_tiles) {
  if (geometry_tiles == 0 || mesh.indices.empty()) return 0;
  std::vector<std::uint32_t> kept;
  kept.reserve(mesh.indices.size());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if ((triangle_tile_mask(mesh, t) & ~geometry_tiles) == 0) continue;
    kept.insert(kept.end(), mesh.indices.begin() + std::ptrdiff_t(3 * t), mesh.indices.begin() + std::ptrdiff_t(3 * t + 3));
  }
  const std::size_t removed = mesh.triangle_count() - kept.size() / 3;
  if (removed == 0) return 0;
  // Keep the vertices still used, in their order.
  constexpr std::uint32_t kUnused = ~std::uint32_t{0};
  std::vector<std::uint32_t> remap(mesh.positions.size(), kUnused);
  for (std::uint32_t i : kept) remap[i] = 0;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < remap.size(); ++v)
    if (remap[v] != kUnused) {
      remap[v] = next;
      mesh.positions[next] = mesh.positions[v];
      if (!mesh.uvs.empty()) mesh.uvs[next] = mesh.uvs[v];
      ++next;
    }
  mesh.positions.resize(next);
  if (!mesh.uvs.empty()) mesh.uvs.resize(next);
  for (std::uint32_t& i : kept) i = remap[i];
  mesh.indices = std::move(kept);
  return removed;
}

}  // namespace cellbake
