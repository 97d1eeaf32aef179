// Stage `cull_box`: exact search for the largest near-field cube within a
// triangle budget. Wilson 2002 §7.3.1.2 binary-searches the half size; here the
// search is replaced by an exact selection of the (budget+1)-th smallest
// triangle Chebyshev distance, bracketed by chunk-level distance intervals so
// that only the chunks that decide the answer are loaded. Per-triangle
// distances use the 13-axis test of Akenine-Möller 2001.
#include "stages/cull_box.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "stages/triangle_box_overlap.h"

namespace cellbake {
namespace {

// A chunk within reach of the search: the Chebyshev distances of all its
// triangles lie in [lo, hi] (conservative, from the indexed bounds). Once
// loaded, each triangle t has its own interval [lower[t], upper[t]] (bounding
// box distance, nearest corner), collapsed to the exact distance on demand.
struct Candidate {
  ChunkRef ref;
  double lo = 0, hi = 0;
  std::shared_ptr<const Chunk> chunk;  // null until loaded
  Vec3d offset;                        // chunk origin - centre
  std::vector<double> lower, upper;
};

inline double linf_norm(const Vec3d& v) { return std::max(std::max(std::fabs(v.x), std::fabs(v.y)), std::fabs(v.z)); }

// Gap kept below the (budget+1)-th distance d*: 256 ulps of the coordinates'
// magnitude (see find_cull_box's contract).
double safety_gap(const Vec3d& center, double d) {
  return 256 * std::numeric_limits<double>::epsilon() * (linf_norm(center) + d);
}

struct Weighted {
  double value;
  std::uint64_t weight;
};

// The smallest value v with (sum of weights of entries <= v) >= k, k >= 1;
// +infinity when the total weight is below k. Weighted quickselect with a
// deterministic median-of-three pivot; reorders `v`.
double weighted_select(std::vector<Weighted>& v, std::uint64_t k) {
  std::size_t begin = 0, end = v.size();
  while (end - begin > 24) {
    const double a = v[begin].value, b = v[begin + (end - begin) / 2].value, c = v[end - 1].value;
    const double pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
    auto first = v.begin() + static_cast<std::ptrdiff_t>(begin),
         last = v.begin() + static_cast<std::ptrdiff_t>(end);
    auto mid_lo = std::partition(first, last, [&](const Weighted& w) { return w.value < pivot; });
    auto mid_hi = std::partition(mid_lo, last, [&](const Weighted& w) { return w.value == pivot; });
    std::uint64_t below = 0, equal = 0;
    for (auto it = first; it != mid_lo; ++it) below += it->weight;
    for (auto it = mid_lo; it != mid_hi; ++it) equal += it->weight;
    if (k <= below) {
      end = static_cast<std::size_t>(mid_lo - v.begin());
    } else if (k <= below + equal) {
      return pivot;
    } else {
      k -= below + equal;
      begin = static_cast<std::size_t>(mid_hi - v.begin());
    }
  }
  std::sort(v.begin() + static_cast<std::ptrdiff_t>(begin), v.begin() + static_cast<std::ptrdiff_t>(end),
            [](const Weighted& x, const Weighted& y) { return x.value < y.value; });
  for (std::size_t i = begin; i < end; ++i) {
    if (k <= v[i].weight) return v[i].value;
    k -= v[i].weight;
  }
  return std::numeric_limits<double>::infinity();
}

Vec3d relative_corner(const Candidate& c, std::uint32_t vertex) {
  const Vec3f& p = c.chunk->positions[vertex];
  return {c.offset.x + p.x, c.offset.y + p.y, c.offset.z + p.z};
}

// Loads the candidate's chunk, checks it against its index entry and computes
// each triangle's distance interval.
void load_chunk(Candidate& cand, const Vec3d& center, const ChunkSource& source, std::uint64_t& loads) {
  cand.chunk = source.load(cand.ref.id);
  ++loads;
  const std::string where = "cull_box: chunk " + std::to_string(cand.ref.id);
  if (!cand.chunk) throw std::runtime_error(where + " loaded as null");
  const Chunk& chunk = *cand.chunk;
  if (chunk.triangle_count() != cand.ref.triangle_count || chunk.indices.size() % 3 != 0)
    throw std::runtime_error(where + " has " + std::to_string(chunk.triangle_count()) +
                             " triangles but the index says " + std::to_string(cand.ref.triangle_count));
  cand.offset = chunk.origin - center;
  std::vector<Vec3d> rel(chunk.positions.size());
  std::vector<double> norm(rel.size());
  for (std::uint32_t i = 0; i < rel.size(); ++i) {
    rel[i] = relative_corner(cand, i);
    norm[i] = linf_norm(rel[i]);
  }
  const std::size_t n = chunk.triangle_count();
  cand.lower.resize(n);
  cand.upper.resize(n);
  const std::uint32_t* idx = chunk.indices.data();
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t i0 = idx[3 * t], i1 = idx[3 * t + 1], i2 = idx[3 * t + 2];
    if (i0 >= rel.size() || i1 >= rel.size() || i2 >= rel.size())
      throw std::runtime_error(where + ": triangle " + std::to_string(t) + " indexes past its " +
                               std::to_string(rel.size()) + " vertices");
    cand.lower[t] = triangle_box_axes_gap(rel[i0], rel[i1], rel[i2]);
    cand.upper[t] = std::min({norm[i0], norm[i1], norm[i2]});
  }
}

// Collapses triangle t's interval to its exact distance.
void refine_triangle(Candidate& cand, std::size_t t) {
  if (cand.lower[t] == cand.upper[t]) return;
  const std::uint32_t* idx = cand.chunk->indices.data() + 3 * t;
  const double d = triangle_linf_distance_relative(
      relative_corner(cand, idx[0]), relative_corner(cand, idx[1]), relative_corner(cand, idx[2]));
  cand.lower[t] = cand.upper[t] = d;
}

void validate(const Vec3d& center, const CullBoxParams& params) {
  if (!is_finite(center)) throw std::invalid_argument("cull_box: cell centre is not finite");
  if (!(params.min_half_size >= 0) || !std::isfinite(params.min_half_size))
    throw std::invalid_argument("cull_box: min_half_size must be finite and >= 0, got " +
                                std::to_string(params.min_half_size));
  if (!(params.max_half_size >= params.min_half_size))
    throw std::invalid_argument("cull_box: max_half_size (" + std::to_string(params.max_half_size) +
                                ") must be >= min_half_size (" + std::to_string(params.min_half_size) + ")");
}

// Candidates of every chunk whose bounds touch cube(center, h) for the
// smallest doubling h >= min_half such that either the chunks wholly inside
// that cube already exceed the budget (so the answer is <= h and no farther
// chunk matters) or h reached `max_half`. Sorted by chunk id.
std::vector<Candidate> gather_candidates(const Vec3d& center, double min_half, double max_half,
                                         std::uint64_t budget, const ChunkSource& source) {
  double h = min_half > 0 ? min_half : max_half / 1024;
  for (;;) {
    h = std::min(h, max_half);
    std::vector<ChunkRef> refs = source.query(Box3d::cube(center, h));
    std::uint64_t inside = 0;
    for (const ChunkRef& r : refs)
      if (!r.bounds.empty() && box_linf_reach(center, r.bounds) <= h) inside += r.triangle_count;
    if (inside > budget || h >= max_half || !(h > 0)) {
      std::vector<Candidate> cands;
      cands.reserve(refs.size());
      for (const ChunkRef& r : refs) {
        if (r.bounds.empty() || r.triangle_count == 0) continue;
        Candidate c;
        c.ref = r;
        c.lo = box_linf_distance(center, r.bounds);
        c.hi = box_linf_reach(center, r.bounds);
        cands.push_back(std::move(c));
      }
      return cands;
    }
    h *= 2;
  }
}

// One unit of the selection: a whole unloaded chunk (triangle == kWholeChunk)
// or one triangle of a loaded chunk, with its distance interval.
constexpr std::uint32_t kWholeChunk = ~0u;
struct Item {
  double lo, hi;
  std::uint32_t cand, triangle;
};

// The (budget+1)-th smallest triangle distance d*, or +infinity when fewer
// triangles are in reach. Works like a bisection that only ever narrows:
// bracket d* between the k-th smallest lower bound and the k-th smallest upper
// bound of the active items, retire items wholly below (they rank before d*)
// or above the bracket, and refine the items that straddle it — load chunks
// holding the bracket's midpoint, then collapse triangles to exact distances —
// until every active item is exact. Stops early (with a value just as good for
// the clamped answer) once d* is known to exceed `max_half` or to be at most
// `min_half`.
double select_threshold(std::vector<Candidate>& cands, const Vec3d& center, std::uint64_t budget,
                        double min_half, double max_half, const ChunkSource& source, std::uint64_t& loads) {
  std::uint64_t total = 0;
  for (const Candidate& c : cands) total += c.ref.triangle_count;
  if (total <= budget) return std::numeric_limits<double>::infinity();

  std::uint64_t k = budget + 1;  // rank of d* among the active items' distances
  std::vector<Item> active;
  for (std::uint32_t i = 0; i < cands.size(); ++i)
    active.push_back({cands[i].lo, cands[i].hi, i, kWholeChunk});
  auto weight = [&](const Item& it) -> std::uint64_t {
    return it.triangle == kWholeChunk ? cands[it.cand].ref.triangle_count : 1;
  };
  std::vector<Weighted> entries;
  for (;;) {
    entries.clear();
    entries.reserve(active.size());
    for (const Item& it : active) entries.push_back({it.lo, weight(it)});
    const double bracket_lo = weighted_select(entries, k);
    entries.clear();
    for (const Item& it : active) entries.push_back({it.hi, weight(it)});
    const double bracket_hi = weighted_select(entries, k);
    if (bracket_lo > max_half) return bracket_lo;   // d* > max: the answer is max
    if (bracket_hi <= min_half) return bracket_hi;  // d* <= min: the budget is exceeded at min

    // Retire items wholly below or above the bracket.
    std::size_t kept = 0;
    bool all_exact = true, any_chunk = false;
    for (const Item& it : active) {
      if (it.hi < bracket_lo) {
        k -= weight(it);
      } else if (it.lo <= bracket_hi) {
        active[kept++] = it;
        all_exact = all_exact && it.lo == it.hi;
        any_chunk = any_chunk || it.triangle == kWholeChunk;
      }
    }
    active.resize(kept);
    if (all_exact) {
      entries.clear();
      for (const Item& it : active) entries.push_back({it.lo, weight(it)});
      return weighted_select(entries, k);
    }

    const double probe = bracket_lo + 0.5 * (bracket_hi - bracket_lo);
    std::vector<Item> next;
    if (any_chunk) {
      // Load the chunks holding the midpoint, or failing that the nearest one.
      std::vector<std::uint32_t> to_load;
      for (const Item& it : active)
        if (it.triangle == kWholeChunk && it.lo <= probe && probe <= it.hi) to_load.push_back(it.cand);
      if (to_load.empty()) {
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t nearest = 0;
        for (const Item& it : active) {
          const double gap = std::max(it.lo - probe, probe - it.hi);
          if (it.triangle == kWholeChunk && gap < best) best = gap, nearest = it.cand;
        }
        to_load.push_back(nearest);
      }
      std::size_t capacity = active.size();
      for (std::uint32_t ci : to_load) capacity += cands[ci].ref.triangle_count;
      next.reserve(capacity);
      for (const Item& it : active)
        if (it.triangle != kWholeChunk || std::find(to_load.begin(), to_load.end(), it.cand) == to_load.end())
          next.push_back(it);
      for (std::uint32_t ci : to_load) {
        Candidate& c = cands[ci];
        load_chunk(c, center, source, loads);
        for (std::uint32_t t = 0; t < c.lower.size(); ++t) {
          if (c.upper[t] < bracket_lo) {
            --k;  // ranks before d*
          } else if (c.lower[t] <= bracket_hi) {
            next.push_back({c.lower[t], c.upper[t], ci, t});
          }
        }
      }
    } else {
      next.reserve(active.size());
      // Only triangles straddle the bracket: make them exact.
      for (Item it : active) {
        if (it.lo != it.hi) {
          refine_triangle(cands[it.cand], it.triangle);
          it.lo = it.hi = cands[it.cand].lower[it.triangle];
        }
        next.push_back(it);
      }
    }
    active.swap(next);
  }
}

// The near field at `half` from candidates covering the cube: the triangles
// whose Chebyshev distance to the centre is at most `half`, per chunk, sorted
// by chunk id (find_cull_box's final evaluation and near_field_at).
void evaluate_near_field(std::vector<Candidate>& cands, const Vec3d& cell_center, double half, const ChunkSource& source,
                         CullBoxResult& result) {
  for (Candidate& c : cands) {
    std::uint64_t n = 0;
    if (!c.chunk && c.hi <= half) {
      n = c.ref.triangle_count;
    } else if (!c.chunk && c.lo > half) {
      n = 0;
    } else {
      if (!c.chunk) load_chunk(c, cell_center, source, result.chunks_loaded);
      for (std::size_t t = 0; t < c.lower.size(); ++t) {
        if (c.upper[t] <= half) {
          ++n;
        } else if (c.lower[t] <= half) {
          refine_triangle(c, t);
          n += c.lower[t] <= half;
        }
      }
    }
    if (n == 0) continue;
    result.triangle_count += n;
    result.near_field.push_back({c.ref.id, static_cast<std::uint32_t>(n), n == c.ref.triangle_count});
  }
  std::sort(result.near_field.begin(), result.near_field.end(),
            [](const NearChunk& a, const NearChunk& b) { return a.chunk_id < b.chunk_id; });
}

}  // namespace

CullBoxResult find_cull_box(const Vec3d& cell_center, const CullBoxParams& params,
                            const ChunkSource& source) {
  validate(cell_center, params);
  const double min_half = params.min_half_size;
  const Box3d model = source.model_bounds();
  const double max_half =
      model.empty() ? min_half
                    : std::max(min_half, std::min(params.max_half_size, box_linf_reach(cell_center, model)));

  CullBoxResult result;
  std::vector<Candidate> cands =
      gather_candidates(cell_center, min_half, max_half, params.triangle_budget, source);
  result.chunks_queried = cands.size();
  const double threshold = select_threshold(cands, cell_center, params.triangle_budget, min_half, max_half,
                                            source, result.chunks_loaded);
  const double half = threshold <= max_half
                          ? std::clamp(threshold - safety_gap(cell_center, threshold), min_half, max_half)
                          : max_half;
  result.half_size = half;

  // Exact evaluation at the chosen half size.
  evaluate_near_field(cands, cell_center, half, source, result);
  result.budget_exceeded_at_min = result.triangle_count > params.triangle_budget;
  return result;
}

CullBoxResult near_field_at(const Vec3d& cell_center, double half_size, const ChunkSource& source) {
  CullBoxParams params;
  params.min_half_size = params.max_half_size = half_size;
  validate(cell_center, params);
  CullBoxResult result;
  result.half_size = half_size;
  // Candidates from a slightly larger cube, so no chunk touching the cube is
  // missed by rounding; the evaluation counts exactly at half_size.
  const double reach = half_size + 1e-9 * (half_size + std::max({std::fabs(cell_center.x), std::fabs(cell_center.y),
                                                                     std::fabs(cell_center.z)}));
  std::vector<Candidate> cands = gather_candidates(cell_center, reach, reach, 0, source);
  result.chunks_queried = cands.size();
  evaluate_near_field(cands, cell_center, half_size, source, result);
  return result;
}

}  // namespace cellbake
