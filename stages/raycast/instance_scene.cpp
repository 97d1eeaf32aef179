// Two-level scene per cube map: Wald et al. 2014, "Embree: a kernel framework
// for efficient CPU ray tracing", ACM TOG 33(4); https://www.embree.org/api.html.
#include "stages/raycast/instance_scene.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "stages/cube_map.h"
#include "stages/sample/sample.h"

namespace cellbake {

std::vector<ChunkRef> cube_chunks(const Vec3d& eye, const Box3d& cull_box, double near_plane,
                                  const ChunkSource& source) {
  std::vector<ChunkRef> all;
  for (int face = 0; face < kCubeFaces; ++face) {
    std::vector<ChunkRef> refs = chunks_in_face(face, eye, cull_box, near_plane, source);
    all.insert(all.end(), refs.begin(), refs.end());
  }
  std::sort(all.begin(), all.end(), [](const ChunkRef& a, const ChunkRef& b) { return a.id < b.id; });
  all.erase(std::unique(all.begin(), all.end(), [](const ChunkRef& a, const ChunkRef& b) { return a.id == b.id; }),
            all.end());
  return all;
}

InstanceScene::InstanceScene(const ChunkBvhCache& cache, std::vector<std::shared_ptr<const ChunkGroupBvh>> groups,
                             const Vec3d& eye, RTCBuildQuality quality)
    : groups_(std::move(groups)) {
  if (groups_.size() == 1) {
    const Vec3d offset = groups_[0]->origin - eye;  // as the instance's translation below
    ray_origin_ = {-static_cast<float>(offset.x), -static_cast<float>(offset.y),
                   -static_cast<float>(offset.z)};
    scene_ = groups_[0]->scene;
    rtcRetainScene(scene_);
    return;
  }
  scene_ = rtcNewScene(cache.device());
  if (!scene_) cache.check_device("rtcNewScene");
  try {
    attach_and_commit(cache, eye, quality);
  } catch (...) {
    rtcReleaseScene(scene_);
    throw;
  }
}

void InstanceScene::attach_and_commit(const ChunkBvhCache& cache, const Vec3d& eye, RTCBuildQuality quality) {
  RTCDevice device = cache.device();
  rtcSetSceneBuildQuality(scene_, quality);
  for (std::size_t i = 0; i < groups_.size(); ++i) {
    const ChunkGroupBvh& bvh = *groups_[i];
    RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    if (!instance) cache.check_device("rtcNewGeometry(instance)");
    rtcSetGeometryInstancedScene(instance, bvh.scene);
    const Vec3d offset = bvh.origin - eye;  // double, then float: eye-relative
    const float transform[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, static_cast<float>(offset.x),
                                 static_cast<float>(offset.y), static_cast<float>(offset.z)};
    rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, transform);
    rtcCommitGeometry(instance);
    rtcAttachGeometryByID(scene_, instance, static_cast<unsigned>(i));
    rtcReleaseGeometry(instance);
  }
  rtcCommitScene(scene_);
  cache.check_device("building a cube map's instance scene");
}

InstanceScene::~InstanceScene() {
  if (scene_) rtcReleaseScene(scene_);
}

}  // namespace cellbake
