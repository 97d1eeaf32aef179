// Bottom-level BVHs of chunks for the Embree sampler, shared by every sampling
// thread of a bake ("one BVH per bake worker set, not per cell"): each chunk
// becomes an Embree scene holding one triangle geometry in the chunk's own
// frame (its float positions relative to its double origin, as stored), built
// the first time some cube map needs it and kept under a byte cap with
// least-recently-used eviction. Cube maps instance these scenes with
// eye-relative translations (stages/raycast/embree_cube_sampler.h), so float
// precision is that of the stored chunk, wherever the model lies.
//
// Embree 3: Wald et al. 2014, "Embree: a kernel framework for efficient CPU ray
// tracing", ACM TOG 33(4); API reference https://www.embree.org/api.html
// (rtcNewScene, RTC_GEOMETRY_TYPE_TRIANGLE, rtcSetDeviceMemoryMonitorFunction).
#pragma once

#include <embree3/rtcore.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <span>
#include <unordered_map>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

// One chunk's committed bottom-level scene and the chunk its attributes
// (colours, normals, uvs, materials) are read from. Geometry 0 of `scene`,
// primitive i = triangle i of `chunk`.
struct ChunkBvh {
  RTCScene scene = nullptr;
  std::shared_ptr<const Chunk> chunk;
  ChunkBvh() = default;
  ChunkBvh(const ChunkBvh&) = delete;
  ChunkBvh& operator=(const ChunkBvh&) = delete;
  ~ChunkBvh();
};

struct ChunkBvhCacheParams {
  // Cap on the bytes the cache holds: Embree's allocations on its device
  // (BVHs, vertex and index buffers, and the top-level scenes of cube maps in
  // flight) plus the chunks' own attribute arrays. Beyond it the least
  // recently used BVHs that no cube map holds are dropped. A cube map whose
  // chunks alone exceed the cap still works (its BVHs are rebuilt next time).
  std::size_t cache_bytes = std::size_t{4} << 30;
  RTCBuildQuality build_quality = RTC_BUILD_QUALITY_MEDIUM;
  // Embree scene flags of the chunk scenes. ROBUST makes the ray/triangle test
  // watertight, so rays through shared edges never slip between triangles.
  int scene_flags = RTC_SCENE_FLAG_ROBUST;
};

struct ChunkBvhCacheStats {
  std::uint64_t builds = 0;           // chunk BVHs built
  std::uint64_t hits = 0;             // requests answered from the cache
  std::uint64_t evictions = 0;
  std::uint64_t triangles_built = 0;  // over all builds
  double build_seconds = 0;           // thread-seconds in loading + building (load included)
  double load_seconds = 0;            // of which in ChunkSource::load
  std::size_t cached_chunks = 0;
  std::size_t device_bytes = 0;       // Embree's current allocations
  std::size_t peak_device_bytes = 0;
  std::size_t chunk_bytes = 0;        // attribute arrays of cached chunks
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

  // The BVHs of `refs`, in order, loading and building those not cached from
  // `source`. Concurrent calls build each chunk once: a caller builds the
  // chunks nobody has claimed yet and waits for the others, so threads that
  // need the same chunks build them in parallel. Throws std::runtime_error for
  // a malformed chunk (naming its id), load errors and Embree errors; a chunk
  // whose build failed is not cached.
  std::vector<std::shared_ptr<const ChunkBvh>> acquire(std::span<const ChunkRef> refs, const ChunkSource& source);

  // Drops least recently used BVHs that nobody else holds until the cache is
  // under its cap (acquire() does this first too). Call when a cube map has
  // released its BVHs.
  void trim();

  // Throws std::runtime_error with Embree's last error on this device, if any.
  void check_device(const char* what) const;

  ChunkBvhCacheStats stats() const;

 private:
  using Result = std::shared_future<std::shared_ptr<const ChunkBvh>>;
  struct Slot {
    Result result;
    bool built = false;
    std::size_t chunk_bytes = 0;
    std::list<std::int64_t>::iterator recency;  // front = most recent
  };

  std::shared_ptr<const ChunkBvh> build(std::int64_t id, const ChunkSource& source, std::size_t& chunk_bytes);
  void evict_beyond_cap();  // caller holds mutex_
  static bool monitor(void* self, ssize_t bytes, bool post);

  ChunkBvhCacheParams params_;
  RTCDevice device_ = nullptr;
  std::atomic<std::int64_t> device_bytes_{0};
  std::atomic<std::int64_t> peak_device_bytes_{0};
  mutable std::mutex mutex_;
  std::unordered_map<std::int64_t, Slot> slots_;
  std::list<std::int64_t> lru_;
  std::size_t chunk_bytes_ = 0;
  ChunkBvhCacheStats stats_;  // counters; sizes filled in by stats()
};

}  // namespace cellbake
