// The sampling backend seam (issue #12): "colour + planar depth of everything
// outside the cull box, six cube faces, from this eye", answered by a GL
// rasteriser (stages/render/gl_cube_sampler.h: OSMesa or EGL) or an Embree ray
// caster (stages/raycast/embree_cube_sampler.h). The per-cell job holds a
// CubeSampler and does not know which backend answers. Every backend follows
// the conventions of stages/cube_map.h and the SampleParams of stages/sample/sample.h
// (supersampling box-filtered by downsample_face), and shades with the light
// model of stages/shading.h; they agree within the parity tolerance of
// tests/test_sample_backends.cpp.
#pragma once

#include <cstdint>
#include <string>

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/geometry.h"
#include "stages/shading.h"
#include "stages/sample/sample.h"

namespace cellbake {

// What a sampler did, summed over a bake's samplers for `bake -v`: cube maps,
// and for a backend that splits them (Embree beyond half its BVH cap) the
// batches traced and the groups skipped as hidden.
struct CubeSamplerWork {
  std::uint64_t cube_maps = 0;
  std::uint64_t batches = 0;
  std::uint64_t groups_hidden = 0;
  CubeSamplerWork& operator+=(const CubeSamplerWork& o) {
    cube_maps += o.cube_maps, batches += o.batches, groups_hidden += o.groups_hidden;
    return *this;
  }
};

class CubeSampler {
 public:
  virtual ~CubeSampler() = default;
  // The light model of every later sample(). Throws std::invalid_argument for
  // non-unit directions or negative or non-finite strengths.
  virtual void set_shading(const ShadingLights& lights) = 0;
  // The cube map at `eye` of everything outside `cull_box` (points strictly
  // inside it are not seen; the eye may lie inside or outside it). Loads only
  // chunks some face can see. Throws std::invalid_argument for bad parameters
  // and passes on load and backend errors. Use one sampler per thread at a time
  // and one model per sampler (chunk ids of different models collide).
  virtual CubeSample sample(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                            const ChunkSource& source) = 0;
  // Call after each unit of work on a pooled thread, so that the sampler may
  // later be used or destroyed from another thread (a GL context is released
  // from the calling thread; backends without thread affinity do nothing).
  virtual void end_work() {}
  // This sampler's work so far (backends that count none: zeros).
  virtual CubeSamplerWork work() const { return {}; }
  // The backend's name: "osmesa", "egl" or "embree".
  virtual std::string backend_name() const = 0;
  // What does the work, for reports: the GL renderer string of a GL backend
  // (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)" or a GPU's name), "CPU" for a ray
  // caster.
  virtual std::string device() const = 0;
};

}  // namespace cellbake
