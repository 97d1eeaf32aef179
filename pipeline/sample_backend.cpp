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

namespace {

struct AutomaticChoice {
  SampleBackend backend = SampleBackend::embree;
  std::string note;  // why a GPU that is present is not used
};

// Probed once per process: device enumeration (no context) everywhere, and
// where a GPU is enumerated one context created on it, so a GPU EGL cannot
// draw on (no permission on its device node, a missing driver part) leaves
// the bake on Embree rather than on EGL's software fallback or failing cells.
const AutomaticChoice& automatic_choice() {
  static const AutomaticChoice choice = [] {
    AutomaticChoice c;
    if (!egl_hardware_device_present()) return c;
    const std::string error = egl_hardware_context_error();
    if (error.empty()) {
      c.backend = SampleBackend::egl;
    } else {
      c.note = "sample.backend \"auto\": a GPU is present but EGL cannot draw on it (" + error +
               "); sampling with embree on the CPU";
    }
    return c;
  }();
  return choice;
}

}  // namespace

SampleBackend resolve_sample_backend(SampleBackend backend) {
  return backend == SampleBackend::automatic ? automatic_choice().backend : backend;
}

const std::string& automatic_backend_note() { return automatic_choice().note; }

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
