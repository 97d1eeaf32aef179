// A GlContext handle that shares one underlying context, so that several
// drawers (ChunkRenderer, which owns its context, and the viewer's textured
// depth-mesh drawer) draw into the same frame with the same GL objects.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "stages/render/gl_context.h"

namespace cellbake {

// Forwards every call to `shared`; the context lives until its last handle goes.
class SharedGlContext final : public GlContext {
 public:
  explicit SharedGlContext(std::shared_ptr<GlContext> shared) : shared_(std::move(shared)) {
    if (!shared_) throw std::invalid_argument("shared_gl_context: null context");
  }
  void make_current() override { shared_->make_current(); }
  void release_current() override { shared_->release_current(); }
  bool is_current() const override { return shared_->is_current(); }
  GlProc get_proc_address(const char* name) const override { return shared_->get_proc_address(name); }
  int width() const override { return shared_->width(); }
  int height() const override { return shared_->height(); }
  std::string backend_name() const override { return shared_->backend_name(); }

 private:
  std::shared_ptr<GlContext> shared_;
};

}  // namespace cellbake
