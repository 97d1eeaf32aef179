// Embree 3 bottom-level scenes per chunk with an LRU byte cap. Embree: Wald et
// al. 2014, "Embree: a kernel framework for efficient CPU ray tracing", ACM TOG
// 33(4); API: https://www.embree.org/api.html.
#include "stages/raycast/chunk_bvh_cache.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::size_t attribute_bytes(const Chunk& c) {
  return c.positions.size() * sizeof(Vec3f) + c.colors.size() * sizeof(Rgba8) + c.uvs.size() * sizeof(Uv) +
         c.normals.size() * sizeof(Vec3f) + c.indices.size() * sizeof(std::uint32_t) +
         c.materials.size() * sizeof(std::uint32_t);
}

// The checks ChunkRenderer makes on upload, plus the optional per-vertex and
// per-triangle arrays the ray caster reads.
void validate_chunk(const Chunk& chunk) {
  const std::string where = "embree: chunk " + std::to_string(chunk.id);
  const std::size_t n = chunk.positions.size();
  const auto per_vertex = [&](std::size_t size, const char* what) {
    if (size != 0 && size != n)
      throw std::runtime_error(where + " has " + std::to_string(size) + " " + what + " for " + std::to_string(n) +
                               " positions");
  };
  per_vertex(chunk.colors.size(), "colours");
  per_vertex(chunk.normals.size(), "normals");
  per_vertex(chunk.uvs.size(), "uvs");
  if (chunk.indices.size() % 3 != 0) throw std::runtime_error(where + " index count is not a multiple of 3");
  if (!chunk.materials.empty() && chunk.materials.size() != chunk.triangle_count())
    throw std::runtime_error(where + " has " + std::to_string(chunk.materials.size()) + " materials for " +
                             std::to_string(chunk.triangle_count()) + " triangles");
  for (std::uint32_t i : chunk.indices)
    if (i >= n) throw std::runtime_error(where + " index " + std::to_string(i) + " out of range");
}

}  // namespace

ChunkBvh::~ChunkBvh() {
  if (scene) rtcReleaseScene(scene);
}

bool ChunkBvhCache::monitor(void* self, ssize_t bytes, bool /*post*/) {
  auto* cache = static_cast<ChunkBvhCache*>(self);
  const std::int64_t now = cache->device_bytes_.fetch_add(bytes, std::memory_order_relaxed) + bytes;
  std::int64_t peak = cache->peak_device_bytes_.load(std::memory_order_relaxed);
  while (now > peak && !cache->peak_device_bytes_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
  }
  return true;  // never refuse an allocation: the cap is enforced by eviction
}

ChunkBvhCache::ChunkBvhCache(ChunkBvhCacheParams params) : params_(params) {
  device_ = rtcNewDevice(nullptr);
  if (!device_)
    throw std::runtime_error("embree: rtcNewDevice failed (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceMemoryMonitorFunction(device_, &ChunkBvhCache::monitor, this);
}

ChunkBvhCache::~ChunkBvhCache() {
  slots_.clear();  // scenes not held elsewhere are released here
  lru_.clear();
  rtcReleaseDevice(device_);  // Embree keeps it alive while scenes held by others remain
}

void ChunkBvhCache::check_device(const char* what) const {
  const RTCError error = rtcGetDeviceError(device_);
  if (error != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " +
                                                        std::to_string(static_cast<int>(error)) + ")");
}

std::shared_ptr<const ChunkBvh> ChunkBvhCache::build(std::int64_t id, const ChunkSource& source,
                                                     std::size_t& chunk_bytes) {
  const auto t0 = Clock::now();
  std::shared_ptr<const Chunk> chunk = source.load(id);
  const double load_seconds = seconds_since(t0);
  if (!chunk) throw std::runtime_error("embree: source returned no chunk for id " + std::to_string(id));
  if (chunk->id != id)
    throw std::runtime_error("embree: source returned chunk " + std::to_string(chunk->id) + " for id " +
                             std::to_string(id));
  validate_chunk(*chunk);
  auto bvh = std::make_shared<ChunkBvh>();
  bvh->chunk = chunk;
  bvh->scene = rtcNewScene(device_);
  if (!bvh->scene) check_device("rtcNewScene");
  rtcSetSceneFlags(bvh->scene, static_cast<RTCSceneFlags>(params_.scene_flags));
  rtcSetSceneBuildQuality(bvh->scene, params_.build_quality);
  const std::size_t vertices = chunk->positions.size(), triangles = chunk->triangle_count();
  if (triangles > 0) {
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geometry) check_device("rtcNewGeometry");
    rtcSetGeometryBuildQuality(geometry, params_.build_quality);
    // Embree's own buffers (it pads them for its 16-byte vector loads).
    auto* position_buffer = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices));
    auto* index_buffer = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles));
    if (!position_buffer || !index_buffer) {
      rtcReleaseGeometry(geometry);
      check_device("rtcSetNewGeometryBuffer");
      throw std::runtime_error("embree: no buffers for chunk " + std::to_string(id));
    }
    static_assert(sizeof(Vec3f) == 3 * sizeof(float));
    std::memcpy(position_buffer, chunk->positions.data(), vertices * sizeof(Vec3f));
    std::memcpy(index_buffer, chunk->indices.data(), chunk->indices.size() * sizeof(std::uint32_t));
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(bvh->scene, geometry, 0);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(bvh->scene);
  check_device(("building the BVH of chunk " + std::to_string(id)).c_str());
  chunk_bytes = attribute_bytes(*chunk);
  const double build_seconds = seconds_since(t0);
  std::lock_guard lock(mutex_);
  ++stats_.builds;
  stats_.triangles_built += triangles;
  stats_.build_seconds += build_seconds;
  stats_.load_seconds += load_seconds;
  return bvh;
}

std::vector<std::shared_ptr<const ChunkBvh>> ChunkBvhCache::acquire(std::span<const ChunkRef> refs,
                                                                    const ChunkSource& source) {
  trim();
  std::vector<Result> results(refs.size());
  // Claim and build one chunk at a time, so that concurrent callers walking
  // the same ids split the builds between them; wait only at the end.
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const std::int64_t id = refs[i].id;
    std::promise<std::shared_ptr<const ChunkBvh>> promise;
    {
      std::lock_guard lock(mutex_);
      auto it = slots_.find(id);
      if (it != slots_.end()) {
        lru_.splice(lru_.begin(), lru_, it->second.recency);
        results[i] = it->second.result;
        ++stats_.hits;
        continue;
      }
      Slot& slot = slots_[id];
      slot.result = promise.get_future().share();
      lru_.push_front(id);
      slot.recency = lru_.begin();
      results[i] = slot.result;
    }
    std::size_t chunk_bytes = 0;
    try {
      std::shared_ptr<const ChunkBvh> bvh = build(id, source, chunk_bytes);
      promise.set_value(std::move(bvh));
      std::lock_guard lock(mutex_);
      Slot& slot = slots_.at(id);
      slot.built = true;
      slot.chunk_bytes = chunk_bytes;
      chunk_bytes_ += chunk_bytes;
    } catch (...) {
      promise.set_exception(std::current_exception());  // waiters see the error too
      std::lock_guard lock(mutex_);
      auto it = slots_.find(id);
      lru_.erase(it->second.recency);
      slots_.erase(it);
      throw;
    }
  }
  std::vector<std::shared_ptr<const ChunkBvh>> out;
  out.reserve(refs.size());
  for (Result& r : results) out.push_back(r.get());  // rethrows another caller's build error
  return out;
}

void ChunkBvhCache::trim() {
  std::lock_guard lock(mutex_);
  evict_beyond_cap();
}

void ChunkBvhCache::evict_beyond_cap() {
  const auto held = [this] {
    return std::size_t(std::max<std::int64_t>(0, device_bytes_.load(std::memory_order_relaxed))) + chunk_bytes_;
  };
  for (auto it = lru_.end(); it != lru_.begin() && held() > params_.cache_bytes;) {
    --it;
    auto slot = slots_.find(*it);
    // Only BVHs no cube map holds free memory when dropped (the slot's future
    // holds one reference).
    if (!slot->second.built || slot->second.result.get().use_count() > 1) continue;
    chunk_bytes_ -= slot->second.chunk_bytes;
    slots_.erase(slot);
    it = lru_.erase(it);
    ++stats_.evictions;
  }
}

ChunkBvhCacheStats ChunkBvhCache::stats() const {
  std::lock_guard lock(mutex_);
  ChunkBvhCacheStats s = stats_;
  s.cached_chunks = slots_.size();
  s.device_bytes = std::size_t(std::max<std::int64_t>(0, device_bytes_.load()));
  s.peak_device_bytes = std::size_t(std::max<std::int64_t>(0, peak_device_bytes_.load()));
  s.chunk_bytes = chunk_bytes_;
  return s;
}

}  // namespace cellbake
