// Which backend answers the sample stage (config `sample.backend`, issue #12),
// and the factory that gives each bake worker thread its CubeSampler
// (stages/sample/cube_sampler.h): "osmesa" and "egl" rasterise with ChunkRenderer on
// a GL context of that kind, "embree" ray-casts on the CPU through one BVH
// cache shared by all of a bake's samplers, "auto" picks EGL when EGL
// can draw on a hardware (GPU) device, else Embree (docs/usage.md "Sampling backends").
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "stages/sample/cube_sampler.h"
#include "stages/raycast/chunk_bvh_cache.h"
#include "stages/raycast/hit_texturing.h"

namespace cellbake {

enum class SampleBackend { osmesa, egl, embree, automatic };

// "osmesa" | "egl" | "embree" | "auto", and back. parse throws
// std::invalid_argument naming the accepted values.
const char* sample_backend_name(SampleBackend backend);
SampleBackend parse_sample_backend(const std::string& name);

// The backend `backend` stands for on this machine: itself, or for
// `automatic` EGL when a GPU device is present and an EGL context can be
// created on it (probed once per process: one context, on a thread of its
// own, only where a GPU is enumerated), else Embree.
SampleBackend resolve_sample_backend(SampleBackend backend);

// Why `automatic` did not pick a GPU that is present ("" when it did, or when
// there is none), for the bake to print.
const std::string& automatic_backend_note();

// What the backend's pixels depend on, for the bake hash: "gl" for osmesa and
// egl (the same shaders; the rasteriser's rules), "embree" for the ray caster
// (pixel-centre rays). `automatic` is resolved first.
const char* sample_backend_pixels(SampleBackend backend);

// Makes one sampler per worker thread for one bake (one model). Thread-safe.
class CubeSamplerFactory {
 public:
  // `embree_cache_bytes`: the byte cap of the Embree BVH cache (unused by the
  // GL backends). Throws std::runtime_error when the backend is not in this
  // build (OSMesa is optional) or Embree fails to start.
  // `texture_cache_bytes`: the cap on decoded textures (per GL sampler; shared
  // by all Embree samplers).
  CubeSamplerFactory(SampleBackend backend, std::size_t embree_cache_bytes,
                     std::size_t texture_cache_bytes = std::size_t{512} << 20);
  // A new sampler (for GL backends: a new context, current on the calling
  // thread). Throws std::runtime_error when the context cannot be created.
  std::unique_ptr<CubeSampler> make() const;
  // The resolved backend.
  SampleBackend backend() const { return backend_; }
  // The shared Embree BVH cache (null for GL backends).
  const ChunkBvhCache* bvh_cache() const { return cache_.get(); }

 private:
  SampleBackend backend_;
  std::size_t texture_cache_bytes_;
  std::shared_ptr<ChunkBvhCache> cache_;
  std::shared_ptr<MipTextureCache> textures_;
};

}  // namespace cellbake
