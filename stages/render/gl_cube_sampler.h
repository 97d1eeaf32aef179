// The GL sampling backend: stages/render/gl_sample_cube.h's sample_cube() on a ChunkRenderer
// (an OSMesa or EGL context), behind the CubeSampler seam of
// stages/sample/cube_sampler.h. Pixel-identical to calling sample_cube() directly.
#pragma once

#include <memory>
#include <string>

#include "stages/sample/cube_sampler.h"
#include "stages/render/chunk_renderer.h"

namespace cellbake {

class GlCubeSampler final : public CubeSampler {
 public:
  // Takes ownership of `renderer` (not null; throws std::invalid_argument).
  // `backend` names it in backend_name() ("osmesa" or "egl").
  GlCubeSampler(std::unique_ptr<ChunkRenderer> renderer, std::string backend);

  void set_shading(const ShadingLights& lights) override { renderer_->set_shading(lights); }
  // sample_cube(eye, cull_box, params, source, renderer).
  CubeSample sample(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                    const ChunkSource& source) override;
  // Releases the GL context from the calling thread.
  void end_work() override { renderer_->release_context(); }
  std::string backend_name() const override { return backend_; }
  std::string device() const override { return renderer_->gl_renderer(); }
  // The renderer, for its statistics.
  const ChunkRenderer& renderer() const { return *renderer_; }

 private:
  std::unique_ptr<ChunkRenderer> renderer_;
  std::string backend_;
};

}  // namespace cellbake
