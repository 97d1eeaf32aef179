// Ray-cast panoramic samples (issue #12). Embree 3: Wald et al. 2014, "Embree:
// a kernel framework for efficient CPU ray tracing", ACM TOG 33(4); coherent
// streams: Fuetterling et al. 2015, JCGT 4(5); https://www.embree.org/api.html.
#include "stages/raycast/embree_cube_sampler.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "stages/raycast/instance_scene.h"
#include "stages/raycast/ray_segments.h"
#include "stages/far/seen_triangles.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// True when no ray of the size x size faces can hit anything inside `box`
// (world) nearer than what it already hit. Per face, in the face's frame
// (right r, up u, forward f; the box's extents there bound it): a ray of the
// face only reaches points with |r| <= f and |u| <= f, so the box's nearest
// reachable depth is f_min = max(f_lo, min |r|, min |u|) (none when above
// f_hi), and its rays are those through the box's projection at depths
// f_min..f_hi (one pixel wider). Hidden when each of those pixels already has
// a depth no greater than f_min (a hit there would not be nearer, and ties
// keep the earlier hit).
bool box_hidden(const Box3d& box, const Vec3d& eye, const std::array<FaceHits, kCubeFaces>& faces, int size) {
  if (box.empty()) return true;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const auto min_abs = [](double lo, double hi) { return lo > 0 ? lo : hi < 0 ? -hi : 0.0; };
  for (int face = 0; face < kCubeFaces; ++face) {
    const FaceBasis b = cube_face_basis(face);
    double r_lo = kInf, r_hi = -kInf, u_lo = kInf, u_hi = -kInf, f_lo = kInf, f_hi = -kInf;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3d c = Vec3d{corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                            corner & 4 ? box.hi.z : box.lo.z} - eye;
      const double r = dot(c, b.right), u = dot(c, b.up), f = dot(c, b.forward);
      r_lo = std::min(r_lo, r), r_hi = std::max(r_hi, r);
      u_lo = std::min(u_lo, u), u_hi = std::max(u_hi, u);
      f_lo = std::min(f_lo, f), f_hi = std::max(f_hi, f);
    }
    const double f_min = std::max({f_lo, min_abs(r_lo, r_hi), min_abs(u_lo, u_hi), 1e-9});
    if (f_min > f_hi) continue;  // out of this face's frustum
    // s = r / f and t = u / f over r, u in their ranges and f in [f_min, f_hi].
    const double s_lo = r_lo / (r_lo >= 0 ? f_hi : f_min), s_hi = r_hi / (r_hi >= 0 ? f_min : f_hi);
    const double t_lo = u_lo / (u_lo >= 0 ? f_hi : f_min), t_hi = u_hi / (u_hi >= 0 ? f_min : f_hi);
    // Column of s: (s + 1) / 2 * size - 0.5; row of t: (1 - t) / 2 * size - 0.5.
    const auto index = [size](double v) { return int(std::clamp(v, 0.0, double(size - 1))); };
    const int col0 = index(std::floor((s_lo + 1) / 2 * size - 0.5) - 1), col1 = index(std::ceil((s_hi + 1) / 2 * size - 0.5) + 1);
    const int row0 = index(std::floor((1 - t_hi) / 2 * size - 0.5) - 1), row1 = index(std::ceil((1 - t_lo) / 2 * size - 0.5) + 1);
    const std::vector<float>& depth = faces[std::size_t(face)].depth;
    for (int row = row0; row <= row1; ++row)
      for (int col = col0; col <= col1; ++col)
        if (double(depth[std::size_t(row) * std::size_t(size) + std::size_t(col)]) > f_min) return false;
  }
  return true;
}

// The groups a cube map traces, and whether they fit one batch (one scene).
struct CubeGroups {
  std::vector<ChunkGroupRefs> groups;  // nearest first unless one_batch
  bool one_batch = true;
};

// Sorts `groups` by the distance of their bounds to `eye`, nearest first.
void sort_nearest_first(std::vector<ChunkGroupRefs>& groups, const Vec3d& eye) {
  std::vector<std::pair<double, std::size_t>> order;
  for (std::size_t i = 0; i < groups.size(); ++i) order.emplace_back(groups[i].bounds.distance_to(eye), i);
  std::sort(order.begin(), order.end());
  std::vector<ChunkGroupRefs> sorted;
  for (const auto& [distance, i] : order) sorted.push_back(std::move(groups[i]));
  groups = std::move(sorted);
}

// The groups of `cache` holding the chunks a cube map at `eye` may see. When
// they exceed one batch, the cache's focus moves to `eye` and they come
// nearest first, so later batches are mostly hidden behind what earlier ones
// hit and are skipped without being built.
CubeGroups choose_groups(ChunkBvhCache& cache, const Vec3d& eye, const Box3d& cull_box, double near_plane,
                         const ChunkSource& source) {
  CubeGroups cube;
  // A model that is one group is traced whole: a cube map sees it unless it
  // lies inside the cull box, and the same BVH answers whichever of its
  // chunks the faces see, so the source's chunk query (~5 % of a cube map on
  // the 12.7 M plant) is skipped.
  cube.groups = cache.all_groups(source);
  if (cube.groups.size() == 1 && cull_box.strictly_contains(cube.groups.front().bounds)) cube.groups.clear();
  if (cube.groups.size() > 1) cube.groups = cache.groups_of(cube_chunks(eye, cull_box, near_plane, source), source);
  std::size_t estimated_bytes = 0;
  for (const ChunkGroupRefs& g : cube.groups) estimated_bytes += g.estimated_bytes;
  cube.one_batch = estimated_bytes <= cache.one_batch_bytes();
  if (!cube.one_batch) {
    cache.set_focus(eye);
    sort_nearest_first(cube.groups, eye);
  }
  return cube;
}

// The next batch of `cube`'s groups from index `next` on, which it advances
// past them: every group when all fit one batch; else groups in order up to
// the cache's batch bytes, skipping (and counting in `hidden`) those that
// box_hidden finds behind the hits in `faces` so far. Empty when none is left.
std::vector<std::size_t> next_batch(const CubeGroups& cube, std::size_t& next, const ChunkBvhCache& cache,
                                    const Vec3d& eye, const std::array<FaceHits, kCubeFaces>& faces, int size,
                                    std::uint64_t& hidden) {
  std::vector<std::size_t> batch;  // groups
  std::size_t bytes = 0;
  for (; next < cube.groups.size(); ++next) {
    const ChunkGroupRefs& g = cube.groups[next];
    if (!cube.one_batch && box_hidden(g.bounds, eye, faces, size)) {
      ++hidden;
      continue;
    }
    if (!cube.one_batch && !batch.empty() && bytes + g.estimated_batch_bytes > cache.batch_bytes()) break;
    batch.push_back(g.group);
    bytes += g.estimated_batch_bytes;
  }
  return batch;
}

}  // namespace

std::vector<std::uint32_t> block_order(int size) {
  std::vector<std::uint32_t> order;
  order.reserve(std::size_t(size) * std::size_t(size));
  for (int band = 0; band < size; band += 4)
    for (int block = 0; block < size; block += 4)
      for (int row = band; row < std::min(size, band + 4); ++row)
        for (int col = block; col < std::min(size, block + 4); ++col)
          order.push_back(std::uint32_t(row) * std::uint32_t(size) + std::uint32_t(col));
  return order;
}

EmbreeCubeSampler::EmbreeCubeSampler(std::shared_ptr<ChunkBvhCache> cache, std::shared_ptr<MipTextureCache> textures)
    : cache_(std::move(cache)),
      textures_(textures ? std::move(textures) : std::make_shared<MipTextureCache>(std::size_t{512} << 20)),
      shader_(shading_lights(ShadingParams{}, Vec3d{0, 0, 1})) {
  if (!cache_) throw std::invalid_argument("embree_cube_sampler: null BVH cache");
}

CubeSample EmbreeCubeSampler::trace_cube(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                                         const ChunkSource& source) {
  validate_sample_inputs(eye, params);
  const HitTexturer texturer(source, *textures_);
  auto t0 = Clock::now();
  const CubeGroups cube = choose_groups(*cache_, eye, cull_box, params.near_plane, source);
  stats_.gather_seconds += seconds_since(t0);
  const int size = params.face_size * params.supersample;
  set_render_size(size);
  std::array<FaceHits, kCubeFaces> faces;
  for (FaceHits& f : faces) f.clear(std::size_t(size) * std::size_t(size));
  FaceTracer tracer(shader_, texturer, eye_relative_box(cull_box, eye), params.near_plane, size, order_, coordinate_,
                    inverse_coordinate_, face_slabs_, stats_, params.colour);
  for (std::size_t next = 0; next < cube.groups.size();) {
    t0 = Clock::now();
    std::vector<std::size_t> batch = next_batch(cube, next, *cache_, eye, faces, size, stats_.groups_hidden);
    if (batch.empty()) break;
    std::vector<std::shared_ptr<const ChunkGroupBvh>> bvhs =
        cache_->acquire_groups(std::move(batch), source, !cube.one_batch);
    stats_.gather_seconds += seconds_since(t0);
    trace_batch(std::move(bvhs), eye, cube.one_batch, tracer, faces);
  }
  return finish_cube(eye, params, faces);
}

void EmbreeCubeSampler::set_render_size(int size) {
  if (order_size_ == size) return;
  order_ = block_order(size);
  coordinate_.resize(std::size_t(size));
  inverse_coordinate_.resize(std::size_t(size));
  for (int i = 0; i < size; ++i) {
    coordinate_[std::size_t(i)] = 2.0 * (i + 0.5) / size - 1.0;  // 0 (odd sizes): slab_interval handles it
    inverse_coordinate_[std::size_t(i)] = 1.0 / coordinate_[std::size_t(i)];
  }
  tile_of_ = pixel_tiles(size);
  order_size_ = size;
}

void EmbreeCubeSampler::trace_batch(std::vector<std::shared_ptr<const ChunkGroupBvh>> bvhs, const Vec3d& eye,
                                    bool one_batch, FaceTracer& tracer, std::array<FaceHits, kCubeFaces>& faces) {
  auto t0 = Clock::now();
  const InstanceScene scene(*cache_, std::move(bvhs), eye);
  stats_.scene_seconds += seconds_since(t0);
  stats_.instances += scene.size();
  ++stats_.batches;
  t0 = Clock::now();
  for (int face = 0; face < kCubeFaces; ++face) tracer.trace(scene, face, faces[std::size_t(face)]);
  cache_->check_device("tracing a cube map");
  stats_.trace_seconds += seconds_since(t0);
  // Traced: this batch's BVHs (let go with its scene on return) may make room
  // for the next batch.
  if (!one_batch) cache_->trim();
}

CubeSample EmbreeCubeSampler::finish_cube(const Vec3d& eye, const SampleParams& params,
                                          std::array<FaceHits, kCubeFaces>& faces) {
  const auto t0 = Clock::now();
  CubeSample sample;
  sample.eye = eye;
  SeenScratch scratch;
  for (int face = 0; face < kCubeFaces; ++face) {
    FaceHits& hits = faces[std::size_t(face)];
    CubeFace& out = sample.faces[std::size_t(face)];
    out = finish_face(hits.color, hits.depth, params);
    out.seen = seen_triangles(hits.chunk, hits.triangle, tile_of_, scratch);
  }
  stats_.trace_seconds += seconds_since(t0);
  ++stats_.cube_maps;
  return sample;
}

CubeSample EmbreeCubeSampler::sample(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                                     const ChunkSource& source) {
  CubeSample result = trace_cube(eye, cull_box, params, source);
  cache_->trim();  // the cube map's scene is gone: its BVHs may be evicted now
  return result;
}

}  // namespace cellbake
