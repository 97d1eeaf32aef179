#include "pipeline/sample_backend.h"

#include <stdexcept>

#include "stages/raycast/embree_cube_sampler.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_context_egl.h"
#include "stages/render/gl_cube_sampler.h"

namespace cellbake {

const char* sample_backend_name(SampleBackend backend) {
  switch (backend) {
    case SampleBackend::osmesa: return "osmesa";
    case SampleBackend::egl: return "egl";
    case SampleBackend::embree: return "embree";
    default: return "auto";
  }
}

SampleBackend parse_sample_backend(const std::string& name) {
  if (name == "osmesa") return SampleBackend::osmesa;
  if (name == "egl") return SampleBackend::egl;
  if (name == "embree") return SampleBackend::embree;
  if (name == "auto") return SampleBackend::automatic;
  throw std::invalid_argument("sample.backend must be \"osmesa\", \"egl\", \"embree\" or \"auto\", got \"" + name +
                              "\"");
}

SampleBackend resolve_sample_backend(SampleBackend backend) {
  if (backend != SampleBackend::automatic) return backend;
  static const bool gpu = egl_hardware_device_present();  // probed once per process (no context is created)
  return gpu ? SampleBackend::egl : SampleBackend::embree;
}

const char* sample_backend_pixels(SampleBackend backend) {
  return resolve_sample_backend(backend) == SampleBackend::embree ? "embree" : "gl";
}

CubeSamplerFactory::CubeSamplerFactory(SampleBackend backend, std::size_t embree_cache_bytes,
                                       std::size_t texture_cache_bytes)
    : backend_(resolve_sample_backend(backend)), texture_cache_bytes_(texture_cache_bytes) {
  if (backend_ == SampleBackend::osmesa && !gl_backend_compiled(GlBackend::osmesa))
    throw std::runtime_error(
        "sample.backend \"osmesa\": this build has no OSMesa (CELLBAKE_WITH_OSMESA=OFF); use \"egl\", \"embree\" or \"auto\"");
  if (backend_ == SampleBackend::embree) {
    ChunkBvhCacheParams params;
    params.cache_bytes = embree_cache_bytes;
    cache_ = std::make_shared<ChunkBvhCache>(params);
    textures_ = std::make_shared<MipTextureCache>(texture_cache_bytes);
  }
}

std::unique_ptr<CubeSampler> CubeSamplerFactory::make() const {
  if (backend_ == SampleBackend::embree) return std::make_unique<EmbreeCubeSampler>(cache_, textures_);
  const GlBackend gl = backend_ == SampleBackend::egl ? GlBackend::egl : GlBackend::osmesa;
  // Drawing goes to framebuffer objects; the default framebuffer is never used.
  ChunkRendererParams params;
  params.texture_cache_bytes = texture_cache_bytes_;
  return std::make_unique<GlCubeSampler>(std::make_unique<ChunkRenderer>(create_gl_context(gl, 1, 1), params),
                                         sample_backend_name(backend_));
}

}  // namespace cellbake
