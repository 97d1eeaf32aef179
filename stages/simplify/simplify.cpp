// Simplification of dense face meshes (see simplify.h for the contract;
// Wilson 2002 ch. 5 §5.2.3 for the error model).
//
// 1. Border rule (simplify_border): which face-border vertices survive, decided
//    from data both neighbouring faces hold bit for bit.
// 2. Outlines (simplify_outline): the staircase outlines of the surface regions
//    (silhouettes, skins, coverage edges) are cut into chains, each straightened
//    once by Douglas-Peucker within boundary_error_px, so both sides of a
//    silhouette get the same line, and repaired until no segments cross.
// 3. Interior: a constrained Delaunay triangulation (CGAL, exact predicates on
//    integer lattice points) of the kept outline and border points, refined by
//    greedy insertion (Garland & Heckbert 1995, "Fast polygonal approximation
//    of terrains and height fields"): every triangle whose plane in (x, y, 1/z)
//    screen space misses one of its region's dense vertices by more than the
//    relative depth bound is queued by its worst miss; the worst in the queue
//    is inserted first, until none is left or the triangle cap is reached with
//    every miss within the cap's looser bound. A world-space plane is an exact
//    plane in (x, y, 1/z), so flat surfaces end as a few large triangles. A
//    violation on a straightened outline segment re-inserts that segment's
//    farthest staircase point instead (all such segments at once, then the
//    triangulation is rebuilt).
//    simplify_tin: the refinement; simplify_cdt: the triangulation and its
//    constraints' owners; simplify_queue: the queue; simplify_face_meter: a
//    triangle's corner vertices and violations; simplify_components: labels.
// Each triangle belongs to the region that holds most of its triangulation
// component (the cells bounded by constraints) and takes, at every corner, the
// dense vertex of that region there (the pixel in the triangle's direction
// where the region meets itself across a skin), so the two sides of a
// silhouette use their own depths on one shared screen-space line.
#include "stages/simplify/simplify.h"

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/simplify/simplify_border.h"
#include "stages/simplify/simplify_grid.h"
#include "stages/simplify/simplify_outline.h"
#include "stages/simplify/simplify_tin.h"

namespace cellbake {
namespace {

std::vector<std::uint32_t> dense_triangles(const FaceMesh& in) { return in.indices; }

FaceMesh compact(const FaceMesh& in, const std::vector<std::uint32_t>& tris) {
  FaceMesh out;
  std::vector<std::uint32_t> remap(in.positions.size(), kNoVertex);
  out.indices.reserve(tris.size());
  for (std::uint32_t v : tris) {
    if (remap[v] == kNoVertex) {
      remap[v] = std::uint32_t(out.positions.size());
      out.positions.push_back(in.positions[v]);
      out.uvs.push_back(in.uvs[v]);
    }
    out.indices.push_back(remap[v]);
  }
  return out;
}

}  // namespace

// What measuring a result needs of the dense mesh it came from: the dense
// vertices, the grid, the regions and the traced (not straightened) outlines.
struct DenseFaceAnalysis {
  std::optional<FaceMesh> owned;
  const FaceMesh* in = nullptr;
  int face_size = 0;
  FaceGrid grid;
  std::optional<FaceRegions> regions;  // unset (and traced too) when the face is too small to simplify
  std::optional<FaceOutlines> traced;

  SimplifyError measure(const FaceMesh& simplified) const {
    return regions ? measure_simplification_error(*in, grid, *regions, *traced, simplified)
                   : measure_simplification_error(*in, simplified, face_size);
  }
};

// The state between the two steps: the dense mesh's analysis (at a stable
// address: the simplifier refers to its grid and regions), the outlines and
// their triangulation, kept so that finishing continues where bounding stopped.
struct FaceSimplification::State {
  std::unique_ptr<DenseFaceAnalysis> dense = std::make_unique<DenseFaceAnalysis>();
  SimplifyParams params;
  std::vector<FixedSegment> fixed;
  std::unique_ptr<TinSimplifier> tin;
  std::size_t triangles_in = 0;
};

FaceSimplification::FaceSimplification(const FaceMesh& in, int face_size, const SimplifyParams& params)
    : state_(std::make_unique<State>()) {
  state_->dense->in = &in;
  start(face_size, params);
}

FaceSimplification::FaceSimplification(FaceMesh&& in, int face_size, const SimplifyParams& params)
    : state_(std::make_unique<State>()) {
  DenseFaceAnalysis& dense = *state_->dense;
  dense.owned.emplace(std::move(in));
  dense.in = &*dense.owned;
  start(face_size, params);
}

FaceSimplification::~FaceSimplification() = default;
FaceSimplification::FaceSimplification(FaceSimplification&&) noexcept = default;
FaceSimplification& FaceSimplification::operator=(FaceSimplification&&) noexcept = default;

void FaceSimplification::start(int face_size, const SimplifyParams& params) {
  if (!(params.depth_error_relative >= 0))
    throw std::invalid_argument("simplify_face_mesh: depth_error_relative must be >= 0");
  if (!(params.boundary_error_px >= 0))
    throw std::invalid_argument("simplify_face_mesh: boundary_error_px must be >= 0");
  if (!(params.max_depth_error_factor >= 1))
    throw std::invalid_argument("simplify_face_mesh: max_depth_error_factor must be >= 1");
  State& st = *state_;
  DenseFaceAnalysis& dense = *st.dense;
  dense.face_size = face_size;
  st.params = params;
  st.triangles_in = dense.in->triangle_count();
  dense.grid = read_face_grid(*dense.in, face_size);
  if (face_size < 4) {  // too small to simplify: the dense mesh is the result
    outline_triangles_ = dense.in->triangle_count();
    return;
  }
  dense.regions = label_face_regions(dense.grid);
  for (const BorderPiece& p : split_face_border(*dense.in, dense.grid, params.depth_error_relative)) {
    if (!p.covered) continue;
    const auto a = border_point(p.side, p.a, face_size), b = border_point(p.side, p.b, face_size);
    st.fixed.push_back({{a[0], a[1]}, {b[0], b[1]}});
  }
  dense.traced = trace_face_outlines(dense.grid, *dense.regions);
  const double eps = params.depth_error_relative, ceiling = eps * params.max_depth_error_factor;
  const auto simplifier = [&](double outline_depth_error) {
    FaceOutlines outlines = *dense.traced;
    straighten_face_outlines(outlines, st.fixed, params.boundary_error_px, outline_depth_error, face_size);
    return std::make_unique<TinSimplifier>(dense.grid, *dense.regions, std::move(outlines), st.fixed, eps,
                                           params.max_triangles, ceiling);
  };
  st.tin = simplifier(eps);
  // When the outlines alone exceed the cap, the cap's looser bound applies
  // from the start, to their straightening too.
  if (st.tin->outline_triangles() > params.max_triangles && ceiling > eps) st.tin = simplifier(ceiling);
  outline_triangles_ = st.tin->outline_triangles();
  // What waits for finish() needs only the dense vertices, to measure too (a
  // third of an owned dense mesh's memory is its triangles).
  if (dense.owned) std::vector<std::uint32_t>().swap(dense.owned->indices);
}

std::size_t FaceSimplification::outline_triangles() const { return outline_triangles_; }

SimplifyResult FaceSimplification::finish() && {
  SimplifyRuler ruler;
  const bool measure = state_ && state_->params.measure_error;
  SimplifyResult result = std::move(*this).finish(ruler);
  if (measure) result.achieved = ruler.measure(result.mesh);
  return result;
}

SimplifyResult FaceSimplification::finish(SimplifyRuler& ruler) && {
  if (!state_) throw std::logic_error("FaceSimplification::finish: already finished");
  std::unique_ptr<State> st = std::move(state_);
  SimplifyResult result;
  const FaceMesh& in = *st->dense->in;
  result.triangles_in = st->triangles_in;
  result.outline_triangles = outline_triangles_;
  double eps = st->params.depth_error_relative;
  if (st->tin) {
    result.mesh = compact(in, st->tin->run());
    eps = st->tin->bound_used();
  } else {
    result.mesh = compact(in, dense_triangles(in));
  }
  result.triangles_out = result.mesh.triangle_count();
  result.depth_error_bound_used = eps;
  result.cap_forced_larger_error = eps > st->params.depth_error_relative;
  st->tin.reset();  // it refers to the analysis handed over below
  ruler.dense_ = std::move(st->dense);
  return result;
}

SimplifyRuler::SimplifyRuler() = default;
SimplifyRuler::~SimplifyRuler() = default;
SimplifyRuler::SimplifyRuler(SimplifyRuler&&) noexcept = default;
SimplifyRuler& SimplifyRuler::operator=(SimplifyRuler&&) noexcept = default;

SimplifyError SimplifyRuler::measure(const FaceMesh& simplified) const {
  if (!dense_) throw std::logic_error("SimplifyRuler::measure: holds no dense mesh");
  return dense_->measure(simplified);
}

SimplifyResult simplify_face_mesh(const FaceMesh& in, int face_size, const SimplifyParams& params) {
  return FaceSimplification(in, face_size, params).finish();
}

}  // namespace cellbake
