#include "runner/walk/truth_ahead.h"

#include <stdexcept>

#include "stages/render/gl_context.h"

namespace cellbake {

TruthAhead::TruthAhead(const ChunkSource& source, const ShadingLights& lights, const SceneDrawOptions& options)
    : source_(source), lights_(lights), options_(options), worker_([this] { run(); }) {}

TruthAhead::~TruthAhead() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void TruthAhead::request(const RenderCamera& camera, int width, int height) {
  {
    std::lock_guard lock(mutex_);
    if (pending_) throw std::logic_error("TruthAhead: a frame is already requested");
    pending_ = true;
    request_ = Request{camera, width, height};
  }
  changed_.notify_all();
}

TruthFrame TruthAhead::take() {
  std::unique_lock lock(mutex_);
  if (!pending_) throw std::logic_error("TruthAhead: no frame requested");
  changed_.wait(lock, [this] { return result_.has_value() || error_ != nullptr; });
  pending_ = false;
  if (error_) {
    std::exception_ptr e = error_;
    error_ = nullptr;
    result_.reset();
    std::rethrow_exception(e);
  }
  TruthFrame out = std::move(*result_);
  result_.reset();
  return out;
}

void TruthAhead::run() {
  std::unique_ptr<SceneDrawer> drawer;
  std::exception_ptr setup_error;
  try {
    drawer = std::make_unique<SceneDrawer>(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), source_);
    drawer->set_shading(lights_);
  } catch (...) {
    setup_error = std::current_exception();
  }
  for (;;) {
    Request r;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || request_.has_value(); });
      if (stop_) break;
      r = *request_;
      request_.reset();
    }
    std::optional<TruthFrame> frame;
    std::exception_ptr error = setup_error;
    if (!error) try {
        TruthFrame f;
        f.stats = drawer->draw_truth(r.camera, r.width, r.height, options_, f.frame);
        frame = std::move(f);
      } catch (...) {
        error = std::current_exception();
      }
    {
      std::lock_guard lock(mutex_);
      if (error) error_ = error;
      else result_ = std::move(frame);
    }
    changed_.notify_all();
  }
  if (drawer) drawer->release_context();
}

}  // namespace cellbake
