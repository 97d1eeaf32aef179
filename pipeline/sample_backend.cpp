#include "pipeline/sample_backend.h"

#include <optional>
#include <stdexcept>
#include <type_traits>

#include "stages/raycast/embree_cube_sampler.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_cube_sampler.h"

namespace cellbake {
namespace {

// GlBackend::egl when this build's gl_context.h has it (the EGL backend is
// added beside this code), else nothing.
template <typename Backend, typename = void>
struct EglEnum {
  static std::optional<Backend> value() { return std::nullopt; }
};
template <typename Backend>
struct EglEnum<Backend, std::void_t<decltype(Backend::egl)>> {
  static std::optional<Backend> value() { return Backend::egl; }
};

}  // namespace

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
  return backend == SampleBackend::automatic ? SampleBackend::embree : backend;
}

const char* sample_backend_pixels(SampleBackend backend) {
  return resolve_sample_backend(backend) == SampleBackend::embree ? "embree" : "gl";
}

CubeSamplerFactory::CubeSamplerFactory(SampleBackend backend, std::size_t embree_cache_bytes)
    : backend_(resolve_sample_backend(backend)) {
  if (backend_ == SampleBackend::egl && !EglEnum<GlBackend>::value())
    throw std::runtime_error("sample.backend \"egl\": this build has no EGL GL backend");
  if (backend_ == SampleBackend::embree) {
    ChunkBvhCacheParams params;
    params.cache_bytes = embree_cache_bytes;
    cache_ = std::make_shared<ChunkBvhCache>(params);
  }
}

std::unique_ptr<CubeSampler> CubeSamplerFactory::make() const {
  if (backend_ == SampleBackend::embree) return std::make_unique<EmbreeCubeSampler>(cache_);
  const GlBackend gl = backend_ == SampleBackend::egl ? *EglEnum<GlBackend>::value() : GlBackend::osmesa;
  // Drawing goes to framebuffer objects; the default framebuffer is never used.
  return std::make_unique<GlCubeSampler>(std::make_unique<ChunkRenderer>(create_gl_context(gl, 1, 1)),
                                         sample_backend_name(backend_));
}

}  // namespace cellbake
