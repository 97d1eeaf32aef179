#include "stages/render/gl_cube_sampler.h"

#include "stages/render/gl_sample_cube.h"

#include <stdexcept>
#include <utility>

namespace cellbake {

GlCubeSampler::GlCubeSampler(std::unique_ptr<ChunkRenderer> renderer, std::string backend)
    : renderer_(std::move(renderer)), backend_(std::move(backend)) {
  if (!renderer_) throw std::invalid_argument("gl_cube_sampler: null renderer");
}

CubeSample GlCubeSampler::sample(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                                 const ChunkSource& source) {
  return sample_cube(eye, cull_box, params, source, *renderer_);
}

}  // namespace cellbake
