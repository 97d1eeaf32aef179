// The top-level Embree scene of one cube map: an instance of each needed
// chunk group's bottom-level scene (stages/raycast/chunk_bvh_cache.h),
// translated by (group origin - eye) computed in double and rounded to float
// once, as ChunkRenderer translates chunks for the GPU. Rays then start at the
// origin of this eye-relative frame, so models 1e6 m from the world origin
// keep the precision of their stored float positions. A single group (a model
// that fits one batch) is traced directly instead, with rays starting at
// minus that translation in the group's frame: the ray Embree's instance
// transform would give (a pure translation inverts exactly), without the
// instance level.
//
// Instancing (two-level BVH): Wald et al. 2014, "Embree: a kernel framework
// for efficient CPU ray tracing", ACM TOG 33(4); API
// https://www.embree.org/api.html (RTC_GEOMETRY_TYPE_INSTANCE).
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <span>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"
#include "stages/raycast/chunk_bvh_cache.h"

namespace cellbake {

// The chunks a cube map at `eye` may show: the union over the six faces of
// chunks_in_face() (stages/sample/sample.h), sorted by id. Loads nothing.
std::vector<ChunkRef> cube_chunks(const Vec3d& eye, const Box3d& cull_box, double near_plane,
                                  const ChunkSource& source);

class InstanceScene {
 public:
  // Builds and commits the scene on the cache's device: instance i (Embree
  // instance id i) is groups[i] (not null) translated to the frame of `eye`.
  // Holds the groups until destroyed. Throws std::runtime_error on Embree errors.
  InstanceScene(const ChunkBvhCache& cache, std::vector<std::shared_ptr<const ChunkGroupBvh>> groups, const Vec3d& eye,
                RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM);
  ~InstanceScene();
  InstanceScene(const InstanceScene&) = delete;
  InstanceScene& operator=(const InstanceScene&) = delete;

  RTCScene scene() const { return scene_; }
  // Where rays from the eye start in scene(): (0, 0, 0) with instances, else
  // the eye in the single group's frame.
  const Vec3f& ray_origin() const { return ray_origin_; }
  // The group a hit lies in: instance `inst_id` (an RTCHit::instID[0]; RTC_INVALID_GEOMETRY_ID
  // when the single group is traced directly).
  const ChunkGroupBvh& instance(unsigned inst_id) const {
    return *groups_[inst_id == RTC_INVALID_GEOMETRY_ID ? 0 : inst_id];
  }
  std::size_t size() const { return groups_.size(); }

 private:
  void attach_and_commit(const ChunkBvhCache& cache, const Vec3d& eye, RTCBuildQuality quality);

  RTCScene scene_ = nullptr;
  Vec3f ray_origin_;
  std::vector<std::shared_ptr<const ChunkGroupBvh>> groups_;
};

}  // namespace cellbake
