// The Embree sampling backend (issue #12): the cube map of everything outside
// the cull box by ray casting instead of rasterising. Per cube map: the groups
// of the chunks some face can see (cube_chunks; a model that is one group,
// the default up to ~19 M triangles, is taken whole without that query) get
// their bottom-level BVHs from a cache shared by all sampling threads (stages/raycast/chunk_bvh_cache.h),
// a top-level scene instances them in the eye's frame (instance_scene.h), and
// one ray per (sub)pixel centre, in the directions of stages/cube_map.h at the
// supersampled resolution, is traced in coherent streams (rtcIntersect1M with
// RTC_INTERSECT_CONTEXT_FLAG_COHERENT, rays ordered in 4 x 4 pixel blocks).
// Each ray covers [near plane, inf) minus the part strictly inside the cull box
// (ray_segments.h), so geometry of a group lying inside the box is never hit
// (the GL path's fragment discard); its depth is the hit's t, which is planar depth because
// the directions have forward component 1; its colour is hit_shading.h's,
// times the material's texel (hit_texturing.h) when it has a texture; a hit
// an alpha test drops is traced again from just behind it.
// The rays of one face against one batch are traced by face_tracer.h.
// Supersampled faces go through downsample_face like the GL path's. When a
// cube map's groups exceed ChunkBvhCache::one_batch_bytes (half the cache's
// cap) it is traced in batches of at most ChunkBvhCache::batch_bytes (a
// quarter of the cap), nearest groups first, each batch's rays
// limited to the nearest hit so far (a tie keeps the earlier batch's hit), so
// memory stays bounded whatever the model size; a group whose bounds lie
// behind every hit its projection covers is skipped unbuilt (occlusion
// culling, exact: none of its surfaces could be nearer).
//
// Differences from the GL rasteriser are those of point sampling at pixel
// centres versus rasterisation rules on triangle edges and float rounding
// (tests/test_sample_backends.cpp states the tolerance).
//
// Embree 3: Wald et al. 2014, ACM TOG 33(4); ray streams: Fuetterling et al.
// 2015, "Efficient ray tracing kernels for modern CPU architectures", JCGT 4(5);
// API https://www.embree.org/api.html (rtcIntersect1M).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "stages/sample/cube_sampler.h"
#include "stages/raycast/chunk_bvh_cache.h"
#include "stages/raycast/face_tracer.h"
#include "stages/raycast/hit_shading.h"
#include "stages/raycast/hit_texturing.h"
#include "stages/raycast/ray_segments.h"

namespace cellbake {

struct EmbreeSamplerStats {
  std::uint64_t cube_maps = 0;
  std::uint64_t rays = 0;           // primary segments traced
  std::uint64_t second_rays = 0;    // second segments (eye outside the cull box)
  std::uint64_t hits = 0;
  std::uint64_t alpha_retraces = 0; // rays traced again behind alpha-tested texels
  std::uint64_t instances = 0;      // chunk instances over all cube maps
  std::uint64_t batches = 0;        // group batches traced (one per cube map unless the cap splits it)
  std::uint64_t groups_hidden = 0;  // groups of split cube maps skipped: hidden behind earlier batches' hits
  double gather_seconds = 0;        // finding chunks + acquiring their BVHs (builds included)
  double scene_seconds = 0;         // building top-level scenes
  double trace_seconds = 0;         // ray setup + tracing + shading + downsampling
};

class EmbreeCubeSampler final : public CubeSampler {
 public:
  // Samples through `cache` (not null; shared with other threads' samplers)
  // and `textures` (shared likewise; null: a cache of its own of 512 MiB).
  explicit EmbreeCubeSampler(std::shared_ptr<ChunkBvhCache> cache, std::shared_ptr<MipTextureCache> textures = nullptr);

  void set_shading(const ShadingLights& lights) override { shader_ = HitShader(lights); }
  // As CubeSampler::sample. Textured materials are sampled as the GL path
  // does (hit_texturing.h); alpha-tested hits let the ray go on behind them.
  CubeSample sample(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                    const ChunkSource& source) override;
  std::string backend_name() const override { return "embree"; }
  std::string device() const override { return "CPU"; }

  const EmbreeSamplerStats& stats() const { return stats_; }
  CubeSamplerWork work() const override { return {stats_.cube_maps, stats_.batches, stats_.groups_hidden}; }
  const ChunkBvhCache& cache() const { return *cache_; }

 private:
  // The cube map at `eye`: its groups chosen, traced batch by batch, finished.
  CubeSample trace_cube(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                        const ChunkSource& source);
  // Makes order_, coordinate_, inverse_coordinate_ and tile_of_ for size x
  // size faces (kept when they already are).
  void set_render_size(int size);
  // Instances `bvhs` in the frame of `eye`, traces the six faces against them
  // into `faces` and, unless the cube map is `one_batch`, trims the cache.
  void trace_batch(std::vector<std::shared_ptr<const ChunkGroupBvh>> bvhs, const Vec3d& eye, bool one_batch,
                   FaceTracer& tracer, std::array<FaceHits, kCubeFaces>& faces);
  // The sample of the traced `faces` (downsampled, their seen triangles listed).
  CubeSample finish_cube(const Vec3d& eye, const SampleParams& params, std::array<FaceHits, kCubeFaces>& faces);

  std::shared_ptr<ChunkBvhCache> cache_;
  std::shared_ptr<MipTextureCache> textures_;
  HitShader shader_;
  EmbreeSamplerStats stats_;
  std::vector<std::uint32_t> order_;  // pixels of a render_size^2 face in 4 x 4 block order
  std::vector<double> coordinate_;    // s of column i (= -t of row i): 2 (i + 0.5) / size - 1
  std::vector<double> inverse_coordinate_;  // 1.0 / coordinate_[i]
  std::vector<std::uint32_t> tile_of_;      // pixel -> its far-field tile (pixel_tile)
  FaceSlabs face_slabs_;                    // of the face being traced
  int order_size_ = 0;
};

// The pixels of a size x size face (row-major indices) in tracing order: bands
// of 4 rows, each band in 4 x 4 blocks left to right, row-major inside a block
// (so consecutive groups of 16 rays are compact 4 x 4 packets).
std::vector<std::uint32_t> block_order(int size);

}  // namespace cellbake
