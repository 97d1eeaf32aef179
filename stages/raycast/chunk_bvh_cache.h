// Bottom-level BVHs of chunk groups for the Embree sampler, shared by every
// sampling thread of a bake ("one BVH per bake worker set, not per cell").
// The model's chunks are partitioned once into spatially compact groups of up
// to `group_triangles` triangles (by default one group when the model fits
// one batch of the cap, else 1 M triangles; median kd-splits of the chunk
// centres on the longest axis, as chunking.h splits triangles); a group
// becomes one Embree scene with one triangle geometry per chunk (float
// positions relative to the group's double origin), built the first time some
// cube map needs one of its chunks and kept under a byte cap with
// least-recently-used eviction (farthest from the latest eye first while cube
// maps are traced in batches: set_focus). Cube maps instance these scenes with
// eye-relative translations (stages/raycast/instance_scene.h), so float
// precision is that of positions relative to the group's centre,
// wherever the model lies (a 10 km group: 0.3 mm). Groups rather than single
// chunks, because every instance a ray enters costs a transform and a second
// BVH descent, and chunk bounds overlap: on the 2 M plant (512 chunks, 512^2
// x 6 rays) one instance per chunk traced in 209 ms, groups of <= 256 k
// triangles in 164 ms, <= 1 M in 121 ms, one flat BVH in 91 ms; on the 12.7 M
// plant 16 groups 163 ms, one 94 ms (bench_raycast_raw, docs/benchmark-history.md
// "Sampling backends (issue #12)").
//
// Embree 3: Wald et al. 2014, "Embree: a kernel framework for efficient CPU ray
// tracing", ACM TOG 33(4); API reference https://www.embree.org/api.html
// (rtcNewScene, RTC_GEOMETRY_TYPE_TRIANGLE, rtcSetDeviceMemoryMonitorFunction).
// Median splits: Wald & Havran 2006, "On building fast kd-trees for ray tracing".
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

// One chunk group's committed bottom-level scene and the chunks its
// attributes (colours, normals, uvs, materials) are read from: geometry i of
// `scene` is chunks[i], its primitive j is triangle j of that chunk, with
// positions relative to `origin`.
struct ChunkGroupBvh {
  RTCScene scene = nullptr;
  Vec3d origin;
  std::vector<std::shared_ptr<const Chunk>> chunks;
  ChunkGroupBvh() = default;
  ChunkGroupBvh(const ChunkGroupBvh&) = delete;
  ChunkGroupBvh& operator=(const ChunkGroupBvh&) = delete;
  ~ChunkGroupBvh();
};

struct ChunkBvhCacheParams {
  // Cap on the bytes the cache holds: Embree's allocations on its device
  // (BVHs, vertex and index buffers, and the top-level scenes of cube maps in
  // flight) plus the chunks' own attribute arrays. Beyond it the least
  // recently used BVHs that no cube map holds are dropped. A cube map whose
  // groups would take more than half the cap (one_batch_bytes()) is traced in
  // batches of groups (stages/raycast/embree_cube_sampler.h), so two threads'
  // cube maps fit in it whatever the model size; groups dropped are rebuilt
  // when needed again.
  std::size_t cache_bytes = std::size_t{4} << 30;
  // Triangles per chunk group at most (a single larger chunk is a group of
  // its own); 1 makes every chunk its own group. 0 (the default):
  // default_group_triangles(), one group when the whole model fits one batch,
  // else groups of <= 1 M triangles.
  std::size_t group_triangles = 0;
  RTCBuildQuality build_quality = RTC_BUILD_QUALITY_MEDIUM;
  // Quality of the BVHs a cube map traced in batches acquires. Batches exist
  // because the model does not fit the cap, so their groups are dropped and
  // rebuilt for nearly every cube map: the build, not the trace, is the cost.
  // Embree's Morton builder (low) built 2 M triangles 2.8x faster than
  // medium's binned SAH and traced 1.5x slower (docs/benchmark-history.md). Cached
  // apart from build_quality's BVHs of the same group, so which cube maps ran
  // first never changes what a cube map traces.
  RTCBuildQuality batch_build_quality = RTC_BUILD_QUALITY_LOW;
  // Embree scene flags of the group scenes. RTC_SCENE_FLAG_ROBUST would make
  // the ray/triangle test watertight; it cost 15 % in tracing on the 2 M plant
  // and changed no parity figure of tests/test_sample_backends.cpp, so it is off.
  int scene_flags = RTC_SCENE_FLAG_NONE;
};

// What groups_of() assumes a group's BVH and chunks take per triangle before it
// is built: Embree's device memory plus the chunk attributes the cache keeps
// (23 B on the 2 M plant), rounded up. Set when Embree held its own copy of
// the index arrays (84 B per triangle at medium quality, 116 B at low, peak);
// with the chunks' arrays shared, 72 B and 104 B, so these now overestimate by
// 12 B, and cube maps go to batches a little early (docs/benchmark-history.md
// "Sampling backends (issue #12)").
constexpr std::size_t kEstimatedBvhBytesPerTriangle = 112;
constexpr std::size_t kEstimatedLowQualityBvhBytesPerTriangle = 140;

// kEstimatedBvhBytesPerTriangle, or the low-quality figure for RTC_BUILD_QUALITY_LOW.
constexpr std::size_t estimated_bvh_bytes_per_triangle(RTCBuildQuality quality) {
  return quality == RTC_BUILD_QUALITY_LOW ? kEstimatedLowQualityBvhBytesPerTriangle : kEstimatedBvhBytesPerTriangle;
}

// The group size ChunkBvhCacheParams::group_triangles = 0 stands for, for a
// model of `model_triangles` under a cap of `cache_bytes`: the whole model
// when its BVH fits one batch (half the cap at kEstimatedBvhBytesPerTriangle:
// up to 19 M triangles for the default 4 GiB), so every cube map traces one
// instance; else 1 M triangles, so batches of nearest groups can skip groups
// hidden behind earlier hits (docs/benchmark-history.md, "82 M triangles").
constexpr std::size_t default_group_triangles(std::uint64_t model_triangles, std::size_t cache_bytes) {
  constexpr std::size_t kBatchedGroupTriangles = std::size_t{1} << 20;
  const bool one_batch = model_triangles * kEstimatedBvhBytesPerTriangle <= cache_bytes / 2;
  return one_batch ? std::max<std::size_t>(1, std::size_t(model_triangles)) : kBatchedGroupTriangles;
}

// Some chunks of a cube map, by the group whose BVH holds them.
struct ChunkGroupRefs {
  std::size_t group = 0;
  Box3d bounds;                  // of all the group's chunks
  std::size_t estimated_bytes = 0;        // of its BVH at ChunkBvhCacheParams::build_quality
  std::size_t estimated_batch_bytes = 0;  // and at batch_build_quality
  std::vector<ChunkRef> refs;    // in the order given
};

struct ChunkBvhCacheStats {
  std::uint64_t builds = 0;           // group BVHs built
  std::uint64_t hits = 0;             // requests answered from the cache
  std::uint64_t evictions = 0;
  std::uint64_t triangles_built = 0;  // over all builds
  double build_seconds = 0;           // thread-seconds in loading + building (load included)
  double load_seconds = 0;            // of which in ChunkSource::load
  std::size_t groups = 0;             // in the model's partition
  std::size_t cached_groups = 0;
  std::size_t device_bytes = 0;       // Embree's current allocations
  std::size_t peak_device_bytes = 0;
  std::size_t chunk_bytes = 0;        // attribute arrays of the cached groups' chunks
};

// Thread-safe; one cache per model (chunk ids of different models collide).
class ChunkBvhCache {
 public:
  // Creates the Embree device. Throws std::runtime_error when Embree fails.
  explicit ChunkBvhCache(ChunkBvhCacheParams params = {});
  ~ChunkBvhCache();
  ChunkBvhCache(const ChunkBvhCache&) = delete;
  ChunkBvhCache& operator=(const ChunkBvhCache&) = delete;

  // The device every scene of this cache lives on (top-level scenes of cube
  // maps must be created on it too).
  RTCDevice device() const { return device_; }

  // The BVHs of the groups holding the chunks `refs`, each once, loading and
  // building those not cached from `source`. The first call partitions the
  // model (source.query(source.model_bounds())). Concurrent calls build each
  // group once: a caller builds the groups nobody has claimed yet and waits
  // for the others, so threads that need the same groups build them in
  // parallel. Throws std::runtime_error for a malformed chunk (naming its
  // id), a chunk not in the model, load errors and Embree errors; a group
  // whose build failed is not cached. `batched`: the BVHs of a cube map traced
  // in batches (built at batch_build_quality, cached apart).
  std::vector<std::shared_ptr<const ChunkGroupBvh>> acquire(std::span<const ChunkRef> refs,
                                                            const ChunkSource& source, bool batched = false);
  // The same for groups given by number (ChunkGroupRefs::group); throws
  // std::invalid_argument for a number out of range.
  std::vector<std::shared_ptr<const ChunkGroupBvh>> acquire_groups(std::vector<std::size_t> groups,
                                                                   const ChunkSource& source,
                                                                   bool batched = false);

  // The groups holding the chunks `refs`, in ascending group order, each
  // with the world bounds and estimated bytes of its whole BVH
  // at both qualities (estimated_bvh_bytes_per_triangle times its chunks'
  // triangles) and the refs among `refs` it holds. Partitions the model like acquire(); throws
  // std::runtime_error for a chunk not in the model.
  std::vector<ChunkGroupRefs> groups_of(std::span<const ChunkRef> refs, const ChunkSource& source);
  // Every group of the model (partitioning it like acquire()), as groups_of()
  // describes them but with no refs: a sampler whose model is one group
  // traces it without asking the source which chunks a cube map sees.
  std::vector<ChunkGroupRefs> all_groups(const ChunkSource& source);
  // What one cube map may hold at once: half the cap, so two threads' cube
  // maps fit in it. A cube map whose groups exceed it acquires them in batches.
  std::size_t one_batch_bytes() const { return params_.cache_bytes / 2; }
  // What one batch of such a cube map holds at most: a quarter of the cap, so
  // that two threads' batches in flight leave half of it for the groups
  // nearest the eyes, which every cube map around them traces first.
  std::size_t batch_bytes() const { return params_.cache_bytes / 4; }
  // Where cube maps are being traced now (the latest eye that traces in
  // batches): beyond the cap, unheld BVHs are dropped farthest from it first
  // rather than least recently used. A cube map's batches run nearest first,
  // so LRU would drop exactly the groups the next cube map needs first.
  void set_focus(const Vec3d& eye);

  // Drops BVHs that nobody else holds (in evict_beyond_cap's order) until the cache is
  // under its cap (acquire() does this first too). Call when a cube map has
  // released its BVHs.
  void trim();

  // Whether group `group`'s BVH (built for batches or not) is cached now.
  bool holds(std::size_t group, bool batched) const;

  // Throws std::runtime_error with Embree's last error on this device, if any.
  void check_device(const char* what) const;

  ChunkBvhCacheStats stats() const;

 private:
  using Result = std::shared_future<std::shared_ptr<const ChunkGroupBvh>>;
  struct Slot {
    Result result;
    bool built = false;
    std::size_t chunk_bytes = 0;
    std::list<std::size_t>::iterator recency;  // front = most recent
  };

  void partition(const ChunkSource& source);  // fills group_of_, members_, group_triangles_ and group_bounds_ once
  std::size_t group_of(std::int64_t chunk_id) const;  // throws for a chunk not in the model
  ChunkGroupRefs described_group(std::size_t group) const;  // bounds and estimates, no refs
  // A cached BVH: its group and whether it was built for batches.
  static std::size_t slot_key(std::size_t group, bool batched) { return group * 2 + (batched ? 1 : 0); }
  std::shared_ptr<const ChunkGroupBvh> build(std::size_t group, RTCBuildQuality quality, const ChunkSource& source,
                                             std::size_t& chunk_bytes);
  void evict_beyond_cap();  // caller holds mutex_: farthest from focus_ first when set, else LRU
  static bool monitor(void* self, ssize_t bytes, bool post);

  ChunkBvhCacheParams params_;
  RTCDevice device_ = nullptr;
  std::atomic<std::int64_t> device_bytes_{0};
  std::atomic<std::int64_t> peak_device_bytes_{0};
  mutable std::mutex mutex_;
  std::once_flag partitioned_;
  std::unordered_map<std::int64_t, std::size_t> group_of_;  // chunk id -> group
  std::vector<std::vector<std::int64_t>> members_;          // group -> chunk ids
  std::vector<std::uint64_t> group_triangles_;              // group -> triangles of its chunks
  std::vector<Box3d> group_bounds_;                         // group -> bounds of its chunks
  std::unordered_map<std::size_t, Slot> slots_;             // by slot_key
  std::list<std::size_t> lru_;                              // slot keys
  std::optional<Vec3d> focus_;                              // set_focus
  std::size_t chunk_bytes_ = 0;
  ChunkBvhCacheStats stats_;  // counters; sizes filled in by stats()
};

}  // namespace cellbake
