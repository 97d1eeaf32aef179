#include "stages/far/far_choice.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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

// What a tile may need of the far geometry: a whole chunk (or its level), or
// one triangle of a chunk, with its triangle count.
struct Element {
  std::uint32_t chunk;     // index into far_chunks
  std::uint32_t triangle;  // kWhole: the whole chunk
  std::uint64_t weight;
};
constexpr std::uint32_t kWhole = ~std::uint32_t{0};

// One choice of choose_far_field with a fixed set of levels (`lods`, one per
// far chunk or empty). Construct it, then call choose() once: it collects
// what each tile would need and what it would drop, runs the greedy passes
// (the whole cell, each face, each tile takes geometry where it pays),
// learns the meshes of the faces that keep depth meshes, and counts the
// result. Missing meshes are learned (bounds first) only where a decision
// depends on them, each source called at most once per face.
class GreedyFarChoice {
 public:
  // Throws std::invalid_argument when `lods` is neither empty nor one per far chunk.
  GreedyFarChoice(const Box3d& eyes, std::span<const ChunkRef> far_chunks, std::span<const FarChoiceSample> samples,
                  FarChoiceMode mode, double geometry_factor, const FarChoiceMeshSource& mesh_source,
                  const FarChoiceBoundSource& bound_source, std::span<const FarLodChoice> lods);
  FarChoice choose();

 private:
  FarLodChoice level_of(std::size_t chunk) const { return lods_.empty() ? FarLodChoice{} : lods_[chunk]; }
  // Index of chunk `id` in far_chunks, or -1 (near field).
  std::int64_t index_of(std::int64_t id) const;

  // Collecting what the tiles need and what they would drop.
  void count_mesh(int face, const FaceMesh& mesh);
  void add_to_tiles(int face, std::uint32_t tiles, std::uint32_t element);
  void collect_chunks_seeing_tiles();
  void collect_seen_elements();
  void mark_seen_chunks(std::vector<char>& whole, std::vector<char>& seen) const;
  void use_levels_cheaper_than_seen(std::vector<char>& whole, const std::vector<char>& seen,
                                    const std::vector<std::size_t>& offset, std::vector<std::uint32_t>& element_of);
  void add_seen_elements(const std::vector<char>& whole, const std::vector<std::size_t>& offset,
                         std::vector<std::uint32_t>& element_of);

  // Learning the meshes and bounds not known yet.
  std::pair<std::uint32_t, std::uint32_t> face_tiles(int face, int first, int count) const;
  // Whether the face's mesh is bounded but not known.
  bool bound_only(std::size_t sample, int face) const {
    return bounded_[sample][std::size_t(face)] && !known_[sample][std::size_t(face)];
  }
  bool learn_one(int first, int count, bool meshes_only);
  std::uint64_t unlearned_faces(int first, int count) const;

  // The greedy passes.
  void take_geometry_where_it_pays();
  bool cell_pass() { return try_group(0, kAllTiles, false); }
  bool face_pass();
  bool tile_pass();
  bool try_group(int first, int count, bool force);
  std::uint64_t group_gain(int first, int count) const;
  bool pays(std::uint64_t extra, std::uint64_t gain, bool force) const {
    return extra + gain > 0 && (force || double(extra) <= geometry_factor_ * double(gain));
  }
  void learn_meshes_kept_as_depth_meshes();

  // The result.
  void count_faces(FarChoice& out);
  void gather_pieces(FarChoice& out) const;

  const Box3d& eyes_;
  const std::span<const ChunkRef> far_chunks_;
  const std::span<const FarChoiceSample> samples_;
  FarChoiceMode mode_;
  const double geometry_factor_;
  const FarChoiceMeshSource& mesh_source_;
  const FarChoiceBoundSource& bound_source_;
  const std::span<const FarLodChoice> lods_;
  std::vector<char> use_level_;  // per far chunk: drawn at its level (whole)
  // What each tile would drop: its depth-mesh triangles, counted from the
  // meshes known so far. Triangles spanning tiles are dropped only when all
  // the tiles they reach take geometry (counted in the gain of the group
  // that completes them, not in any one tile's).
  std::vector<std::uint64_t> removable_;
  // Per face: how many spanning triangles reach each set of tiles (sorted by
  // tile set), and the union of those sets.
  std::array<std::vector<std::pair<std::uint32_t, std::uint64_t>>, kCubeFaces> spanning_;
  std::array<std::uint32_t, kCubeFaces> spanned_tiles_{};
  std::vector<std::array<char, kCubeFaces>> known_;  // per sample and face: mesh counted
  std::array<int, kCubeFaces> missing_{};            // per face: samples whose mesh is not known yet
  std::vector<char> geometry_;                       // per tile: takes geometry
  // Lower bounds on the triangles of meshes not known yet (bounded: asked for).
  std::vector<std::array<std::uint64_t, kCubeFaces>> bound_;
  std::vector<std::array<char, kCubeFaces>> bounded_;
  // Over the meshes and bounds learned (a mesh replaces its bound).
  std::uint64_t learned_triangles_ = 0, learned_faces_ = 0;
  std::vector<Element> elements_;
  std::vector<std::vector<std::uint32_t>> tile_elements_;  // per tile: its elements, ascending
  std::vector<char> chosen_;                               // per element: drawn
  std::vector<std::uint32_t> stamp_of_;                    // per element: last stamp_ that counted it
  std::uint32_t stamp_ = 0;
};

}  // namespace

FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                           const FarChoiceMeshSource& mesh_source, const FarChoiceBoundSource& bound_source,
                           std::span<const FarLodChoice> lods) {
  if (lods.empty())
    return GreedyFarChoice(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, bound_source, lods).choose();
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
      GreedyFarChoice(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, bound_source, levels).choose();
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
  return GreedyFarChoice(eyes, far_chunks, samples, mode, geometry_factor, mesh_source, bound_source, levels).choose();
}

namespace {

GreedyFarChoice::GreedyFarChoice(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                                 std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                                 const FarChoiceMeshSource& mesh_source, const FarChoiceBoundSource& bound_source,
                                 std::span<const FarLodChoice> lods)
    : eyes_(eyes),
      far_chunks_(far_chunks),
      samples_(samples),
      mode_(mode),
      geometry_factor_(geometry_factor),
      mesh_source_(mesh_source),
      bound_source_(bound_source),
      lods_(lods) {
  if (!lods.empty() && lods.size() != far_chunks.size())
    throw std::invalid_argument("choose_far_field: " + std::to_string(lods.size()) + " level choices for " +
                                std::to_string(far_chunks.size()) + " far chunks");
  use_level_.assign(far_chunks.size(), 0);
  removable_.assign(kAllTiles, 0);
  known_.resize(samples.size());
  geometry_.assign(kAllTiles, 0);
  bound_.resize(samples.size());
  bounded_.resize(samples.size());
  tile_elements_.resize(kAllTiles);
}

FarChoice GreedyFarChoice::choose() {
  for (std::size_t i = 0; i < samples_.size(); ++i)
    for (int f = 0; f < kCubeFaces; ++f) {
      known_[i][std::size_t(f)] = samples_[i].meshes[std::size_t(f)] != nullptr || !mesh_source_;
      if (samples_[i].meshes[std::size_t(f)]) count_mesh(f, *samples_[i].meshes[std::size_t(f)]);
      missing_[std::size_t(f)] += !known_[i][std::size_t(f)];
    }
  if (samples_.empty()) {
    mode_ = FarChoiceMode::geometry;
    collect_chunks_seeing_tiles();
  } else {
    collect_seen_elements();
  }
  chosen_.assign(elements_.size(), 0);
  stamp_of_.assign(elements_.size(), 0);
  take_geometry_where_it_pays();
  learn_meshes_kept_as_depth_meshes();
  FarChoice out;
  count_faces(out);
  gather_pieces(out);
  return out;
}

std::int64_t GreedyFarChoice::index_of(std::int64_t id) const {
  const auto it = std::lower_bound(far_chunks_.begin(), far_chunks_.end(), id,
                                   [](const ChunkRef& c, std::int64_t v) { return c.id < v; });
  return it != far_chunks_.end() && it->id == id ? it - far_chunks_.begin() : -1;
}

// Counts a newly known mesh of face `face`: its triangles within one tile in
// that tile's removable_, those spanning tiles in spanning_ by tile set.
void GreedyFarChoice::count_mesh(int face, const FaceMesh& mesh) {
  auto& sets = spanning_[std::size_t(face)];
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const int tile = triangle_tile(mesh, t);
    if (tile >= 0) {
      ++removable_[std::size_t(face * kFarTilesPerFace + tile)];
      continue;
    }
    const std::uint32_t tiles = triangle_tile_mask(mesh, t);
    spanned_tiles_[std::size_t(face)] |= tiles;
    const auto it = std::lower_bound(sets.begin(), sets.end(), std::make_pair(tiles, std::uint64_t{0}));
    if (it != sets.end() && it->first == tiles)
      ++it->second;
    else
      sets.insert(it, {tiles, 1});
  }
}

// Element `element` is needed by the tiles `tiles` (bits as in
// FaceFarChoice::geometry_tiles) of face `face`.
void GreedyFarChoice::add_to_tiles(int face, std::uint32_t tiles, std::uint32_t element) {
  for (int k = 0; k < kFarTilesPerFace; ++k)
    if (tiles >> k & 1u) tile_elements_[std::size_t(face * kFarTilesPerFace + k)].push_back(element);
}

// Without samples: every far chunk whole (or at its level where that is
// cheaper), needed by every tile whose frustum from the eyes reaches it.
void GreedyFarChoice::collect_chunks_seeing_tiles() {
  for (std::size_t i = 0; i < far_chunks_.size(); ++i) {
    const FarLodChoice l = level_of(i);
    use_level_[i] = l.level > 0 && l.triangles < far_chunks_[i].triangle_count;
    elements_.push_back({std::uint32_t(i), kWhole, use_level_[i] ? l.triangles : far_chunks_[i].triangle_count});
    for (int f = 0; f < kCubeFaces; ++f)
      add_to_tiles(f, tiles_seeing_box(f, eyes_, far_chunks_[i].bounds), std::uint32_t(elements_.size() - 1));
  }
}

// With samples: per far chunk seen, whole (any sample saw it whole, or its
// level replaces what was seen) or its triangles; element ids through a
// dense per-triangle table of the chunks seen.
void GreedyFarChoice::collect_seen_elements() {
  std::vector<char> whole(far_chunks_.size(), 0), seen(far_chunks_.size(), 0);
  mark_seen_chunks(whole, seen);
  std::vector<std::size_t> offset(far_chunks_.size() + 1, 0);
  for (std::size_t i = 0; i < far_chunks_.size(); ++i)
    offset[i + 1] = offset[i] + (seen[i] && !whole[i] ? far_chunks_[i].triangle_count : 0);
  std::vector<std::uint32_t> element_of(offset.back(), kWhole);
  if (!lods_.empty()) use_levels_cheaper_than_seen(whole, seen, offset, element_of);
  add_seen_elements(whole, offset, element_of);
  for (auto& list : tile_elements_) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
}

// Which far chunks some sample saw, and saw whole.
void GreedyFarChoice::mark_seen_chunks(std::vector<char>& whole, std::vector<char>& seen) const {
  for (const FarChoiceSample& sample : samples_)
    for (const auto* list : sample.seen)
      if (list)
        for (const SeenChunk& c : *list)
          if (const std::int64_t i = index_of(c.id); i >= 0) {
            seen[std::size_t(i)] = 1;
            if (c.whole()) whole[std::size_t(i)] = 1;
          }
}

// A chunk's level replaces what was seen of it (the chunk becomes whole, at
// its level) when it costs fewer triangles. `element_of` serves as the
// distinct triangles' marks and is left all kWhole.
void GreedyFarChoice::use_levels_cheaper_than_seen(std::vector<char>& whole, const std::vector<char>& seen,
                                                   const std::vector<std::size_t>& offset,
                                                   std::vector<std::uint32_t>& element_of) {
  std::vector<std::uint64_t> seen_count(far_chunks_.size(), 0);
  for (std::size_t i = 0; i < far_chunks_.size(); ++i)
    if (whole[i]) seen_count[i] = far_chunks_[i].triangle_count;
  for (const FarChoiceSample& sample : samples_)
    for (const auto* list : sample.seen)
      if (list)
        for (const SeenChunk& c : *list)
          if (const std::int64_t i = index_of(c.id); i >= 0 && !whole[std::size_t(i)])
            for (std::uint32_t t : c.triangles)
              if (t < far_chunks_[std::size_t(i)].triangle_count && element_of[offset[std::size_t(i)] + t] == kWhole)
                element_of[offset[std::size_t(i)] + t] = 0, ++seen_count[std::size_t(i)];
  std::fill(element_of.begin(), element_of.end(), kWhole);
  for (std::size_t i = 0; i < far_chunks_.size(); ++i) {
    const FarLodChoice l = level_of(i);
    use_level_[i] = seen[i] && l.level > 0 && l.triangles < seen_count[i];
    if (use_level_[i]) whole[i] = 1;
  }
}

// The elements of what the samples saw, in sample, face and seen-list order,
// each added to the tiles that saw it.
void GreedyFarChoice::add_seen_elements(const std::vector<char>& whole, const std::vector<std::size_t>& offset,
                                        std::vector<std::uint32_t>& element_of) {
  std::vector<std::uint32_t> whole_element(far_chunks_.size(), kWhole);
  for (const FarChoiceSample& sample : samples_)
    for (int f = 0; f < kCubeFaces; ++f) {
      if (!sample.seen[std::size_t(f)]) continue;
      for (const SeenChunk& c : *sample.seen[std::size_t(f)]) {
        const std::int64_t i = index_of(c.id);
        if (i < 0) continue;
        const std::size_t ci = std::size_t(i);
        if (whole[ci]) {
          if (whole_element[ci] == kWhole) {
            whole_element[ci] = std::uint32_t(elements_.size());
            elements_.push_back(
                {std::uint32_t(ci), kWhole, use_level_[ci] ? level_of(ci).triangles : far_chunks_[ci].triangle_count});
          }
          add_to_tiles(f, c.tiles, whole_element[ci]);
          continue;
        }
        for (std::size_t k = 0; k < c.triangles.size(); ++k) {
          const std::uint32_t t = c.triangles[k];
          if (t >= far_chunks_[ci].triangle_count) continue;  // not this chunk's: ignore
          std::uint32_t& e = element_of[offset[ci] + t];
          if (e == kWhole) {
            e = std::uint32_t(elements_.size());
            elements_.push_back({std::uint32_t(ci), t, 1});
          }
          add_to_tiles(f, c.triangle_tiles[k], e);
        }
      }
    }
}

// Face `face`'s tiles (bits as in FaceFarChoice::geometry_tiles) already
// taken, and those of the group first..first+count-1 not taken yet.
std::pair<std::uint32_t, std::uint32_t> GreedyFarChoice::face_tiles(int face, int first, int count) const {
  std::uint32_t taken = 0, open = 0;
  for (int b = 0; b < kFarTilesPerFace; ++b) {
    const int k = face * kFarTilesPerFace + b;
    if (geometry_[std::size_t(k)])
      taken |= 1u << b;
    else if (k >= first && k < first + count)
      open |= 1u << b;
  }
  return std::make_pair(taken, open);
}

// Learns about a missing mesh of a face with a tile in first..first+count-1
// not taken yet: the bound of one whose face the group covers wholly open
// (there every triangle counts, so the bound does too), else the mesh;
// each time the largest guess, then the first in sample and face order.
// False when no mesh is missing there.
bool GreedyFarChoice::learn_one(int first, int count, bool meshes_only) {
  std::size_t best_sample = 0;
  int best_face = -1;
  bool best_bound = false;
  for (std::size_t i = 0; i < samples_.size(); ++i)
    for (int f = first / kFarTilesPerFace; f <= (first + count - 1) / kFarTilesPerFace; ++f) {
      if (known_[i][std::size_t(f)]) continue;
      const auto [taken, open] = face_tiles(f, first, count);
      if (open == 0) continue;
      const bool by_bound =
          bound_source_ && !meshes_only && !bounded_[i][std::size_t(f)] && taken == 0 && open == kFaceTiles;
      const std::uint64_t guess = samples_[i].mesh_guess[std::size_t(f)];
      if (best_face >= 0 &&
          (by_bound != best_bound ? best_bound
                                  : guess <= samples_[best_sample].mesh_guess[std::size_t(best_face)]))
        continue;
      best_sample = i, best_face = f, best_bound = by_bound;
    }
  if (best_face < 0) return false;
  const std::size_t f = std::size_t(best_face);
  if (best_bound) {
    bounded_[best_sample][f] = 1;
    bound_[best_sample][f] = bound_source_(best_sample, best_face);
    learned_triangles_ += bound_[best_sample][f], ++learned_faces_;
    return true;
  }
  known_[best_sample][f] = 1;
  --missing_[f];
  const FaceMesh& mesh = mesh_source_(best_sample, best_face);
  count_mesh(best_face, mesh);
  if (bounded_[best_sample][f])
    learned_triangles_ = learned_triangles_ - bound_[best_sample][f] + mesh.triangle_count();
  else
    learned_triangles_ += mesh.triangle_count(), ++learned_faces_;
  return true;
}

// Faces with a tile in the group not taken yet whose mesh is neither known
// nor bounded.
std::uint64_t GreedyFarChoice::unlearned_faces(int first, int count) const {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < samples_.size(); ++i)
    for (int f = first / kFarTilesPerFace; f <= (first + count - 1) / kFarTilesPerFace; ++f)
      n += !known_[i][std::size_t(f)] && !bounded_[i][std::size_t(f)] && face_tiles(f, first, count).second != 0;
  return n;
}

// Mode geometry: the whole cell takes geometry, whatever it costs. Mode
// cheapest: the passes over the whole cell, each face and each tile, repeated
// until none takes more. Mode tdm: nothing.
void GreedyFarChoice::take_geometry_where_it_pays() {
  if (mode_ == FarChoiceMode::geometry) {
    try_group(0, kAllTiles, true);
  } else if (mode_ == FarChoiceMode::cheapest) {
    for (bool changed = true; changed;) {
      const bool cell = cell_pass();
      const bool faces = face_pass();
      const bool tiles = tile_pass();
      changed = cell || faces || tiles;
    }
  }
}

// Each face, as one group, takes geometry where it pays; true when any did.
bool GreedyFarChoice::face_pass() {
  bool changed = false;
  for (int f = 0; f < kCubeFaces; ++f) changed = try_group(f * kFarTilesPerFace, kFarTilesPerFace, false) || changed;
  return changed;
}

// Each tile alone takes geometry where it pays; true when any did.
bool GreedyFarChoice::tile_pass() {
  bool changed = false;
  for (int k = 0; k < kAllTiles; ++k) changed = try_group(k, 1, false) || changed;
  return changed;
}

// Takes geometry for the group's tiles not taken yet when it pays (always
// with `force`); true when it took some. The gain known so far is a lower
// bound: it decides "yes" at once, while a "no" first learns the group's
// missing meshes one by one.
bool GreedyFarChoice::try_group(int first, int count, bool force) {
  ++stamp_;
  std::uint64_t extra = 0;
  bool any = false;
  for (int k = first; k < first + count; ++k) {
    if (geometry_[std::size_t(k)]) continue;
    any = true;
    for (std::uint32_t e : tile_elements_[std::size_t(k)])
      if (!chosen_[e] && stamp_of_[e] != stamp_) stamp_of_[e] = stamp_, extra += elements_[e].weight;
  }
  if (!any) return false;
  // Bounds are asked for while they may decide: while the faces not
  // learned yet, at the mean size of those learned, could make the group
  // pay. Otherwise meshes are (the decision is exact either way; this only
  // saves holding bounded faces that will be meshed anyway).
  if (!(force && extra > 0))
    for (std::uint64_t g = group_gain(first, count); !pays(extra, g, force); g = group_gain(first, count)) {
      const bool promising =
          learned_faces_ == 0 ||
          pays(extra, g + unlearned_faces(first, count) * learned_triangles_ / learned_faces_, force);
      if (!learn_one(first, count, !promising)) return false;
    }
  for (int k = first; k < first + count; ++k) {
    if (geometry_[std::size_t(k)]) continue;
    if (tile_elements_[std::size_t(k)].empty() && removable_[std::size_t(k)] == 0 &&
        missing_[std::size_t(k / kFarTilesPerFace)] == 0 &&
        !(spanned_tiles_[std::size_t(k / kFarTilesPerFace)] >> (k % kFarTilesPerFace) & 1u))
      continue;
    geometry_[std::size_t(k)] = 1;
    for (std::uint32_t e : tile_elements_[std::size_t(k)]) chosen_[e] = 1;
  }
  return true;
}

// The depth-mesh triangles taking the group drops: those within its open
// tiles, and those spanning tiles that all draw geometry once it is taken.
std::uint64_t GreedyFarChoice::group_gain(int first, int count) const {
  std::uint64_t g = 0;
  for (int k = first; k < first + count; ++k)
    if (!geometry_[std::size_t(k)]) g += removable_[std::size_t(k)];
  for (int f = first / kFarTilesPerFace; f <= (first + count - 1) / kFarTilesPerFace; ++f) {
    const auto [taken, open] = face_tiles(f, first, count);
    if (open == 0) continue;
    for (const auto& [tiles, n] : spanning_[std::size_t(f)])
      if ((tiles & ~(taken | open)) == 0 && (tiles & open) != 0) g += n;
    if (taken == 0 && open == kFaceTiles)  // the whole face goes: so do the bounded meshes' triangles
      for (std::size_t i = 0; i < samples_.size(); ++i)
        if (bound_only(i, f)) g += bound_[i][std::size_t(f)];
  }
  return g;
}

// A face keeping depth meshes anywhere needs all its meshes (tdm mode, or
// tiles no geometry pays for).
void GreedyFarChoice::learn_meshes_kept_as_depth_meshes() {
  for (int f = 0; f < kCubeFaces; ++f)
    for (int k = 0; k < kFarTilesPerFace && missing_[std::size_t(f)] > 0; ++k)
      if (!geometry_[std::size_t(f * kFarTilesPerFace + k)])
        while (learn_one(f * kFarTilesPerFace, kFarTilesPerFace, true)) {
        }
}

// Each face's geometry tiles and its triangle counts (FaceFarChoice).
void GreedyFarChoice::count_faces(FarChoice& out) {
  for (int f = 0; f < kCubeFaces; ++f) {
    FaceFarChoice& face = out.faces[std::size_t(f)];
    ++stamp_;
    for (int k = 0; k < kFarTilesPerFace; ++k) {
      const std::size_t tile = std::size_t(f * kFarTilesPerFace + k);
      if (!geometry_[tile]) {
        face.tdm_triangles += removable_[tile];
        continue;
      }
      face.geometry_tiles |= 1u << k;
      face.replaced_triangles += removable_[tile];
      for (std::uint32_t e : tile_elements_[tile])
        if (stamp_of_[e] != stamp_) stamp_of_[e] = stamp_, face.geometry_triangles += elements_[e].weight;
    }
    for (const auto& [tiles, n] : spanning_[std::size_t(f)])
      ((tiles & ~face.geometry_tiles) == 0 ? face.replaced_triangles : face.tdm_triangles) += n;
    for (std::size_t i = 0; i < samples_.size(); ++i)  // meshes never learned: their faces are all geometry
      if (bound_only(i, f)) face.replaced_triangles += bound_[i][std::size_t(f)];
  }
}

// The chosen elements grouped into pieces by chunk (chunks ascend by id),
// and their triangles in all.
void GreedyFarChoice::gather_pieces(FarChoice& out) const {
  std::vector<std::uint32_t> order;
  for (std::uint32_t e = 0; e < elements_.size(); ++e)
    if (chosen_[e]) order.push_back(e);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return elements_[a].chunk != elements_[b].chunk ? elements_[a].chunk < elements_[b].chunk
                                                    : elements_[a].triangle < elements_[b].triangle;
  });
  for (std::uint32_t e : order) {
    const Element& el = elements_[e];
    if (out.pieces.empty() || out.pieces.back().chunk.id != far_chunks_[el.chunk].id) {
      out.pieces.push_back({far_chunks_[el.chunk], {}});
      if (use_level_[el.chunk]) {
        out.pieces.back().level = level_of(el.chunk).level;
        out.pieces.back().level_triangles = level_of(el.chunk).triangles;
      }
    }
    if (el.triangle != kWhole) out.pieces.back().triangles.push_back(el.triangle);
  }
  for (const FarPiece& p : out.pieces) out.geometry_triangles += p.triangle_count();
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
  seen.triangles.clear();
  seen.triangle_tiles.clear();
  seen.tiles = 0;
  const auto take = [&](std::uint32_t t) {
    seen.triangles.push_back(t);
    seen.triangle_tiles.push_back(scratch[t]);
    seen.tiles |= scratch[t];
    scratch[t] = 0;
  };
  if (touched.empty()) return;
  // Ascending: sorted, or (when the set fills much of its span, as grown
  // rings do) read off the scratch, where exactly the touched are non-zero.
  const auto [lo, hi] = std::minmax_element(touched.begin(), touched.end());
  if (std::size_t(*hi - *lo) < 8 * touched.size()) {
    for (std::uint32_t t = *lo, end = *hi; t <= end; ++t)
      if (scratch[t] != 0) take(t);
  } else {
    std::sort(touched.begin(), touched.end());
    for (const std::uint32_t t : touched) take(t);
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
