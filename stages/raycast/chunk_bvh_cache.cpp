// Embree 3 bottom-level scenes per chunk group with an LRU byte cap. Embree:
// Wald et al. 2014, "Embree: a kernel framework for efficient CPU ray tracing",
// ACM TOG 33(4); API: https://www.embree.org/api.html. Groups by median
// kd-splits: Wald & Havran 2006, "On building fast kd-trees for ray tracing".
#include "stages/raycast/chunk_bvh_cache.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "stages/tsan_handoff.h"

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

// Median kd-split of chunk refs on the longest axis of their centres' bounds
// until each part holds at most `cap` triangles (or one chunk).
void split_groups(std::vector<ChunkRef>& refs, std::size_t begin, std::size_t end, std::size_t cap,
                  std::vector<std::vector<std::int64_t>>& groups) {
  std::size_t triangles = 0;
  for (std::size_t i = begin; i < end; ++i) triangles += refs[i].triangle_count;
  if (triangles <= cap || end - begin <= 1) {
    std::vector<std::int64_t> ids;
    for (std::size_t i = begin; i < end; ++i) ids.push_back(refs[i].id);
    std::sort(ids.begin(), ids.end());
    groups.push_back(std::move(ids));
    return;
  }
  Box3d centres;
  for (std::size_t i = begin; i < end; ++i) centres.expand(refs[i].bounds.center());
  const Vec3d e = centres.extent();
  const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
  const std::size_t middle = begin + (end - begin) / 2;
  std::nth_element(refs.begin() + std::ptrdiff_t(begin), refs.begin() + std::ptrdiff_t(middle),
                   refs.begin() + std::ptrdiff_t(end), [axis](const ChunkRef& a, const ChunkRef& b) {
                     const double ca = a.bounds.center()[axis], cb = b.bounds.center()[axis];
                     return ca != cb ? ca < cb : a.id < b.id;  // deterministic
                   });
  split_groups(refs, begin, middle, cap, groups);
  split_groups(refs, middle, end, cap, groups);
}

}  // namespace

ChunkGroupBvh::~ChunkGroupBvh() {
  if (scene) rtcReleaseScene(scene);
}

bool ChunkBvhCache::monitor(void* self, ssize_t bytes, bool /*post*/) {
  auto* cache = static_cast<ChunkBvhCache*>(self);
  const std::int64_t now = cache->device_bytes_.fetch_add(bytes, std::memory_order_relaxed) + bytes;
  std::int64_t peak = cache->peak_device_bytes_.load(std::memory_order_relaxed);
  while (now > peak && !cache->peak_device_bytes_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
  }
  // Called on Embree's build threads too: see ~ChunkBvhCache.
  tsan::before(cache);
  return true;  // never refuse an allocation: the cap is enforced by eviction
}

ChunkBvhCache::ChunkBvhCache(ChunkBvhCacheParams params) : params_(params) {
  device_ = rtcNewDevice(nullptr);
  if (!device_)
    throw std::runtime_error("embree: rtcNewDevice failed (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceMemoryMonitorFunction(device_, &ChunkBvhCache::monitor, this);
}

ChunkBvhCache::~ChunkBvhCache() {
  // Every monitor() call, some on Embree's TBB build threads (joined inside
  // rtcCommitScene), happens before the cache is destroyed (stages/tsan_handoff.h).
  tsan::after(this);
  slots_.clear();  // scenes not held elsewhere are released here
  lru_.clear();
  // Scenes still held elsewhere free their memory later, with this cache gone:
  // from here on the device must not call monitor() with a dangling pointer.
  rtcSetDeviceMemoryMonitorFunction(device_, nullptr, nullptr);
  rtcReleaseDevice(device_);  // Embree keeps it alive while scenes held by others remain
}

void ChunkBvhCache::check_device(const char* what) const {
  const RTCError error = rtcGetDeviceError(device_);
  if (error != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " +
                                                        std::to_string(static_cast<int>(error)) + ")");
}

void ChunkBvhCache::partition(const ChunkSource& source) {
  std::call_once(partitioned_, [&] {
    std::vector<ChunkRef> refs = source.query(source.model_bounds());
    std::erase_if(refs, [](const ChunkRef& r) { return r.bounds.empty(); });
    std::vector<std::vector<std::int64_t>> groups;
    std::uint64_t model_triangles = 0;
    for (const ChunkRef& r : refs) model_triangles += r.triangle_count;
    const std::size_t limit = params_.group_triangles > 0
                                  ? params_.group_triangles
                                  : default_group_triangles(model_triangles, params_.cache_bytes);
    if (!refs.empty()) split_groups(refs, 0, refs.size(), limit, groups);
    std::unordered_map<std::int64_t, std::size_t> group_of;
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (std::int64_t id : groups[g]) group_of[id] = g;
    std::vector<std::uint64_t> triangles(groups.size(), 0);
    std::vector<Box3d> bounds(groups.size());
    for (const ChunkRef& r : refs) {
      triangles[group_of.at(r.id)] += r.triangle_count;
      bounds[group_of.at(r.id)].expand(r.bounds);
    }
    std::lock_guard lock(mutex_);
    members_ = std::move(groups);
    group_of_ = std::move(group_of);
    group_triangles_ = std::move(triangles);
    group_bounds_ = std::move(bounds);
  });
}

std::size_t ChunkBvhCache::group_of(std::int64_t chunk_id) const {
  auto it = group_of_.find(chunk_id);  // immutable after partition()
  if (it == group_of_.end())
    throw std::runtime_error("embree: chunk " + std::to_string(chunk_id) + " is not in the model's chunk list");
  return it->second;
}

ChunkGroupRefs ChunkBvhCache::described_group(std::size_t group) const {
  ChunkGroupRefs g;
  g.group = group;
  g.bounds = group_bounds_[group];
  g.estimated_bytes =
      std::size_t(group_triangles_[group]) * estimated_bvh_bytes_per_triangle(params_.build_quality);
  g.estimated_batch_bytes =
      std::size_t(group_triangles_[group]) * estimated_bvh_bytes_per_triangle(params_.batch_build_quality);
  return g;
}

std::vector<ChunkGroupRefs> ChunkBvhCache::groups_of(std::span<const ChunkRef> refs, const ChunkSource& source) {
  partition(source);
  std::vector<std::pair<std::size_t, std::size_t>> by_group;  // (group, index into refs)
  by_group.reserve(refs.size());
  for (std::size_t i = 0; i < refs.size(); ++i) by_group.emplace_back(group_of(refs[i].id), i);
  std::sort(by_group.begin(), by_group.end());
  std::vector<ChunkGroupRefs> out;
  for (const auto& [group, index] : by_group) {
    if (out.empty() || out.back().group != group) out.push_back(described_group(group));
    out.back().refs.push_back(refs[index]);
  }
  return out;
}

std::vector<ChunkGroupRefs> ChunkBvhCache::all_groups(const ChunkSource& source) {
  partition(source);
  std::vector<ChunkGroupRefs> out;
  for (std::size_t group = 0; group < members_.size(); ++group) out.push_back(described_group(group));
  return out;
}

std::shared_ptr<const ChunkGroupBvh> ChunkBvhCache::build(std::size_t group, RTCBuildQuality quality,
                                                          const ChunkSource& source, std::size_t& chunk_bytes) {
  const auto t0 = Clock::now();
  auto bvh = std::make_shared<ChunkGroupBvh>();
  Box3d bounds;
  for (std::int64_t id : members_[group]) {  // members_ is immutable after partition()
    std::shared_ptr<const Chunk> chunk = source.load(id);
    if (!chunk) throw std::runtime_error("embree: source returned no chunk for id " + std::to_string(id));
    if (chunk->id != id)
      throw std::runtime_error("embree: source returned chunk " + std::to_string(chunk->id) + " for id " +
                               std::to_string(id));
    validate_chunk(*chunk);
    bounds.expand(chunk->bounds);
    bvh->chunks.push_back(std::move(chunk));
  }
  const double load_seconds = seconds_since(t0);
  bvh->origin = bounds.empty() ? Vec3d{} : bounds.center();
  bvh->scene = rtcNewScene(device_);
  if (!bvh->scene) check_device("rtcNewScene");
  rtcSetSceneFlags(bvh->scene, static_cast<RTCSceneFlags>(params_.scene_flags));
  rtcSetSceneBuildQuality(bvh->scene, quality);
  std::size_t triangles = 0;
  chunk_bytes = 0;
  for (std::size_t i = 0; i < bvh->chunks.size(); ++i) {
    const Chunk& chunk = *bvh->chunks[i];
    chunk_bytes += attribute_bytes(chunk);
    const std::size_t vertices = chunk.positions.size(), count = chunk.triangle_count();
    if (count == 0) continue;  // geometry ids stay chunk indices: this one is simply absent
    triangles += count;
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geometry) check_device("rtcNewGeometry");
    rtcSetGeometryBuildQuality(geometry, quality);
    // Positions in Embree's own buffer (in the group frame; Embree pads it
    // for its 16-byte vector loads). The index buffer is the chunk's own
    // array, shared, not copied: the BVH holds the chunk for its lifetime,
    // and index buffers need no padding.
    auto* position_buffer = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices));
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, chunk.indices.data(), 0,
                               3 * sizeof(std::uint32_t), count);
    if (const RTCError error = rtcGetDeviceError(device_); !position_buffer || error != RTC_ERROR_NONE) {
      rtcReleaseGeometry(geometry);
      throw std::runtime_error("embree: no buffers for chunk " + std::to_string(chunk.id) + " (error " +
                               std::to_string(static_cast<int>(error)) + ")");
    }
    // Chunk frame -> group frame in double, rounded to float once: a vertex
    // that two chunks store at the same world position lands on the same
    // float in the group, so shared edges across chunks stay watertight.
    const Vec3d d = chunk.origin - bvh->origin;
    for (std::size_t v = 0; v < vertices; ++v) {
      const Vec3f& p = chunk.positions[v];
      position_buffer[3 * v] = static_cast<float>(double(p.x) + d.x);
      position_buffer[3 * v + 1] = static_cast<float>(double(p.y) + d.y);
      position_buffer[3 * v + 2] = static_cast<float>(double(p.z) + d.z);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(bvh->scene, geometry, static_cast<unsigned>(i));
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(bvh->scene);
  check_device(("building the BVH of chunk group " + std::to_string(group)).c_str());
  const double build_seconds = seconds_since(t0);
  std::lock_guard lock(mutex_);
  ++stats_.builds;
  stats_.triangles_built += triangles;
  stats_.build_seconds += build_seconds;
  stats_.load_seconds += load_seconds;
  return bvh;
}

std::vector<std::shared_ptr<const ChunkGroupBvh>> ChunkBvhCache::acquire(std::span<const ChunkRef> refs,
                                                                         const ChunkSource& source,
                                                                         bool batched) {
  partition(source);
  std::vector<std::size_t> groups;
  groups.reserve(refs.size());
  for (const ChunkRef& r : refs) groups.push_back(group_of(r.id));
  return acquire_groups(std::move(groups), source, batched);
}

std::vector<std::shared_ptr<const ChunkGroupBvh>> ChunkBvhCache::acquire_groups(
    std::vector<std::size_t> groups, const ChunkSource& source, bool batched) {
  const RTCBuildQuality quality = batched ? params_.batch_build_quality : params_.build_quality;
  partition(source);
  trim();
  for (std::size_t group : groups)
    if (group >= members_.size())
      throw std::invalid_argument("embree: chunk group " + std::to_string(group) + " out of range");
  std::sort(groups.begin(), groups.end());
  groups.erase(std::unique(groups.begin(), groups.end()), groups.end());
  std::vector<Result> results(groups.size());
  // Claim and build one group at a time, so that concurrent callers walking
  // the same groups split the builds between them; wait only at the end.
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const std::size_t group = groups[i], key = slot_key(group, batched);
    std::promise<std::shared_ptr<const ChunkGroupBvh>> promise;
    {
      std::lock_guard lock(mutex_);
      auto it = slots_.find(key);
      if (it != slots_.end()) {
        lru_.splice(lru_.begin(), lru_, it->second.recency);
        results[i] = it->second.result;
        ++stats_.hits;
        continue;
      }
      Slot& slot = slots_[key];
      slot.result = promise.get_future().share();
      lru_.push_front(key);
      slot.recency = lru_.begin();
      results[i] = slot.result;
    }
    std::size_t chunk_bytes = 0;
    try {
      std::shared_ptr<const ChunkGroupBvh> bvh = build(group, quality, source, chunk_bytes);
      promise.set_value(std::move(bvh));
      std::lock_guard lock(mutex_);
      Slot& slot = slots_.at(key);
      slot.built = true;
      slot.chunk_bytes = chunk_bytes;
      chunk_bytes_ += chunk_bytes;
    } catch (...) {
      promise.set_exception(std::current_exception());  // waiters see the error too
      std::lock_guard lock(mutex_);
      auto it = slots_.find(key);
      lru_.erase(it->second.recency);
      slots_.erase(it);
      throw;
    }
  }
  std::vector<std::shared_ptr<const ChunkGroupBvh>> out;
  out.reserve(results.size());
  for (Result& r : results) out.push_back(r.get());  // rethrows another caller's build error
  return out;
}

void ChunkBvhCache::trim() {
  std::lock_guard lock(mutex_);
  evict_beyond_cap();
}

bool ChunkBvhCache::holds(std::size_t group, bool batched) const {
  std::lock_guard lock(mutex_);
  const auto slot = slots_.find(slot_key(group, batched));
  return slot != slots_.end() && slot->second.built;
}

void ChunkBvhCache::set_focus(const Vec3d& eye) {
  std::lock_guard lock(mutex_);
  focus_ = eye;
}

void ChunkBvhCache::evict_beyond_cap() {
  const auto held = [this] {
    return std::size_t(std::max<std::int64_t>(0, device_bytes_.load(std::memory_order_relaxed))) + chunk_bytes_;
  };
  if (held() <= params_.cache_bytes) return;
  // Candidates in the order they go: farthest from the focus first (without
  // one, all at distance 0), least recently used first among equals.
  std::vector<std::pair<double, std::list<std::size_t>::iterator>> order;
  for (auto it = lru_.end(); it != lru_.begin();) {
    --it;
    order.emplace_back(focus_ ? group_bounds_[*it / 2].distance_to(*focus_) : 0.0, it);
  }
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [distance, it] : order) {
    if (held() <= params_.cache_bytes) break;
    auto slot = slots_.find(*it);
    // Only BVHs no cube map holds free memory when dropped (the slot's future
    // holds one reference).
    if (!slot->second.built || slot->second.result.get().use_count() > 1) continue;
    chunk_bytes_ -= slot->second.chunk_bytes;
    slots_.erase(slot);
    lru_.erase(it);
    ++stats_.evictions;
  }
}

ChunkBvhCacheStats ChunkBvhCache::stats() const {
  std::lock_guard lock(mutex_);
  ChunkBvhCacheStats s = stats_;
  s.groups = members_.size();
  s.cached_groups = slots_.size();
  s.device_bytes = std::size_t(std::max<std::int64_t>(0, device_bytes_.load()));
  s.peak_device_bytes = std::size_t(std::max<std::int64_t>(0, peak_device_bytes_.load()));
  s.chunk_bytes = chunk_bytes_;
  return s;
}

}  // namespace cellbake
