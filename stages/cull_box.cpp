// Stage `cull_box`: exact search for the largest near-field cube within a
// triangle budget. Wilson 2002 §7.3.1.2 binary-searches the half size; here the
// search is replaced by an exact selection of the (budget+1)-th smallest
// triangle Chebyshev distance, bracketed by chunk-level distance intervals so
// that only the chunks that decide the answer are loaded. Per-triangle
// distances use the 13-axis test of Akenine-Möller 2001.
#include "stages/cull_box.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "stages/triangle_box_overlap.h"

namespace cellbake {
namespace {

// A chunk within reach of the search: the Chebyshev distances of all its
// triangles lie in [lo, hi] (conservative, from the indexed bounds).
struct Candidate {
  ChunkRef ref;
  double lo = 0, hi = 0;
  bool loaded = false;
  // One per triangle, once loaded: the exact Chebyshev distance, or a lower
  // bound of it when that bound already exceeded every half size the search
  // can still return (so "distance <= h" is decided the same either way).
  std::vector<double> distances;
};

double linf_norm(const Vec3d& v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

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
    auto first = v.begin() + static_cast<std::ptrdiff_t>(begin), last = v.begin() + static_cast<std::ptrdiff_t>(end);
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

// Loads the candidate's chunk and computes the Chebyshev distance of each of
// its triangles to `center`. Every half size the search can still return lies
// in [surely_in, surely_out]: a triangle whose bounding-box distance (a lower
// bound) exceeds surely_out keeps that bound, and one whose nearest corner (an
// upper bound) is within surely_in keeps that; both decide "distance <= h"
// exactly as the exact value would, for a fraction of the cost.
void load_distances(Candidate& cand, const Vec3d& center, double surely_in, double surely_out,
                    const ChunkSource& source, std::uint64_t& loads) {
  const std::shared_ptr<const Chunk> chunk = source.load(cand.ref.id);
  ++loads;
  const std::string where = "cull_box: chunk " + std::to_string(cand.ref.id);
  if (!chunk) throw std::runtime_error(where + " loaded as null");
  if (chunk->triangle_count() != cand.ref.triangle_count || chunk->indices.size() % 3 != 0)
    throw std::runtime_error(where + " has " + std::to_string(chunk->triangle_count()) +
                             " triangles but the index says " + std::to_string(cand.ref.triangle_count));
  const Vec3d offset = chunk->origin - center;
  std::vector<Vec3d> rel(chunk->positions.size());
  for (std::size_t i = 0; i < rel.size(); ++i) {
    const Vec3f& p = chunk->positions[i];
    rel[i] = {offset.x + p.x, offset.y + p.y, offset.z + p.z};
  }
  cand.distances.resize(chunk->triangle_count());
  const std::uint32_t* idx = chunk->indices.data();
  for (std::size_t t = 0; t < cand.distances.size(); ++t) {
    const std::uint32_t i0 = idx[3 * t], i1 = idx[3 * t + 1], i2 = idx[3 * t + 2];
    if (i0 >= rel.size() || i1 >= rel.size() || i2 >= rel.size())
      throw std::runtime_error(where + ": triangle " + std::to_string(t) + " indexes past its " +
                               std::to_string(rel.size()) + " vertices");
    const Vec3d& a = rel[i0];
    const Vec3d& b = rel[i1];
    const Vec3d& c = rel[i2];
    const double lower = triangle_box_axes_gap(a, b, c);
    if (lower > surely_out) {
      cand.distances[t] = lower;
      continue;
    }
    const double upper = std::min({linf_norm(a), linf_norm(b), linf_norm(c)});
    cand.distances[t] = upper <= surely_in ? upper : triangle_linf_distance_relative(a, b, c);
  }
  cand.loaded = true;
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
std::vector<Candidate> gather_candidates(const Vec3d& center, double min_half, double max_half, std::uint64_t budget,
                                         const ChunkSource& source) {
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

// The (budget+1)-th smallest triangle distance d*, or +infinity when fewer
// triangles are in reach. Stops early (returning a value that is just as good
// for the clamped answer) once d* is known to exceed `max_half` or to be at
// most `min_half`.
double select_threshold(std::vector<Candidate>& cands, const Vec3d& center, std::uint64_t budget, double min_half,
                        double max_half, const ChunkSource& source, std::uint64_t& loads) {
  std::uint64_t total = 0;
  for (const Candidate& c : cands) total += c.ref.triangle_count;
  if (total <= budget) return std::numeric_limits<double>::infinity();

  std::uint64_t k = budget + 1;              // rank of d* among the still-active distances
  std::vector<std::size_t> pending;          // unloaded candidates still straddling the bracket
  for (std::size_t i = 0; i < cands.size(); ++i) pending.push_back(i);
  std::vector<double> points;                // loaded distances inside the bracket
  std::vector<Weighted> entries;
  for (;;) {
    // Bracket [lo_k, hi_k] with lo_k <= d* <= hi_k: the k-th smallest lower
    // bound and the k-th smallest upper bound.
    entries.clear();
    entries.reserve(pending.size() + points.size());
    for (std::size_t i : pending) entries.push_back({cands[i].lo, cands[i].ref.triangle_count});
    for (double d : points) entries.push_back({d, 1});
    const double bracket_lo = weighted_select(entries, k);
    entries.clear();
    for (std::size_t i : pending) entries.push_back({cands[i].hi, cands[i].ref.triangle_count});
    for (double d : points) entries.push_back({d, 1});
    const double bracket_hi = weighted_select(entries, k);
    if (bracket_lo > max_half) return bracket_lo;  // d* > max: the answer is max
    if (bracket_hi <= min_half) return bracket_hi;  // d* <= min: the budget is exceeded at min

    // Everything wholly below the bracket ranks before d*; everything above after.
    std::vector<std::size_t> straddling;
    for (std::size_t i : pending) {
      if (cands[i].hi < bracket_lo) {
        k -= cands[i].ref.triangle_count;
      } else if (cands[i].lo <= bracket_hi) {
        straddling.push_back(i);
      }
    }
    pending.swap(straddling);
    std::size_t kept = 0;
    for (double d : points) {
      if (d < bracket_lo) {
        --k;
      } else if (d <= bracket_hi) {
        points[kept++] = d;
      }
    }
    points.resize(kept);
    if (pending.empty()) {
      entries.clear();
      for (double d : points) entries.push_back({d, 1});
      return weighted_select(entries, k);
    }

    // Load the pending chunks whose interval holds the bracket's midpoint, or
    // failing that the one nearest to it.
    const double probe = bracket_lo + 0.5 * (bracket_hi - bracket_lo);
    std::vector<std::size_t> to_load, rest;
    for (std::size_t i : pending) (cands[i].lo <= probe && probe <= cands[i].hi ? to_load : rest).push_back(i);
    if (to_load.empty()) {
      auto gap = [&](std::size_t i) { return std::max(cands[i].lo - probe, probe - cands[i].hi); };
      auto nearest = std::min_element(rest.begin(), rest.end(), [&](std::size_t a, std::size_t b) { return gap(a) < gap(b); });
      to_load.push_back(*nearest);
      rest.erase(nearest);
    }
    for (std::size_t i : to_load) {
      // Later half sizes are >= bracket_lo - safety gap, except max_half when d* > max_half.
      const double surely_in = std::min(bracket_lo - 2 * safety_gap(center, bracket_hi), max_half);
      load_distances(cands[i], center, surely_in, bracket_hi, source, loads);
      for (double d : cands[i].distances) {
        if (d < bracket_lo) {
          --k;
        } else if (d <= bracket_hi) {
          points.push_back(d);
        }
      }
    }
    pending.swap(rest);
  }
}

}  // namespace

CullBoxResult find_cull_box(const Vec3d& cell_center, const CullBoxParams& params, const ChunkSource& source) {
  validate(cell_center, params);
  const double min_half = params.min_half_size;
  const Box3d model = source.model_bounds();
  const double max_half =
      model.empty() ? min_half : std::max(min_half, std::min(params.max_half_size, box_linf_reach(cell_center, model)));

  CullBoxResult result;
  std::vector<Candidate> cands = gather_candidates(cell_center, min_half, max_half, params.triangle_budget, source);
  result.chunks_queried = cands.size();
  const double threshold =
      select_threshold(cands, cell_center, params.triangle_budget, min_half, max_half, source, result.chunks_loaded);

  double half = max_half;
  if (threshold <= max_half) {
    half = std::clamp(threshold - safety_gap(cell_center, threshold), min_half, max_half);
  }
  result.half_size = half;

  // Exact evaluation at the chosen half size.
  for (Candidate& c : cands) {
    std::uint64_t n = 0;
    if (!c.loaded && c.hi <= half) {
      n = c.ref.triangle_count;
    } else if (!c.loaded && c.lo > half) {
      n = 0;
    } else {
      if (!c.loaded) load_distances(c, cell_center, half, half, source, result.chunks_loaded);
      n = static_cast<std::uint64_t>(std::count_if(c.distances.begin(), c.distances.end(), [&](double d) { return d <= half; }));
    }
    if (n == 0) continue;
    result.triangle_count += n;
    result.near_field.push_back({c.ref.id, static_cast<std::uint32_t>(n), n == c.ref.triangle_count});
  }
  std::sort(result.near_field.begin(), result.near_field.end(),
            [](const NearChunk& a, const NearChunk& b) { return a.chunk_id < b.chunk_id; });
  result.budget_exceeded_at_min = result.triangle_count > params.triangle_budget;
  return result;
}

}  // namespace cellbake
