// OSMesa backend of GlContext: a core profile context (OSMesaCreateContextAttribs
// with OSMESA_PROFILE = OSMESA_CORE_PROFILE, version 3.3 or newer) rendering
// into a host-memory RGBA buffer.
#include "stages/render/gl_context_osmesa.h"

#include <GL/osmesa.h>

#include <stdexcept>
#include <vector>

namespace cellbake {
namespace {

class OsMesaContext final : public GlContext {
 public:
  OsMesaContext(int width, int height)
      : width_(width), height_(height), buffer_(static_cast<std::size_t>(width) * height * 4) {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           0,  // drawing goes to framebuffer objects with their own depth buffers
                           OSMESA_STENCIL_BITS,
                           0,
                           OSMESA_ACCUM_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           3,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           3,
                           0};
    context_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!context_)
      throw std::runtime_error("gl_context(osmesa): OSMesaCreateContextAttribs failed for an OpenGL 3.3 core profile");
    try {
      make_current();
    } catch (...) {
      OSMesaDestroyContext(context_);
      throw;
    }
  }
  ~OsMesaContext() override {
    release_current();
    OSMesaDestroyContext(context_);
  }
  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;

  void make_current() override {
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_))
      throw std::runtime_error("gl_context(osmesa): OSMesaMakeCurrent failed (" + std::to_string(width_) + "x" +
                               std::to_string(height_) + ")");
  }
  void release_current() override {
    if (is_current()) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  }
  bool is_current() const override { return OSMesaGetCurrentContext() == context_; }
  GlProc get_proc_address(const char* name) const override { return OSMesaGetProcAddress(name); }
  int width() const override { return width_; }
  int height() const override { return height_; }
  std::string backend_name() const override { return "osmesa"; }

 private:
  int width_;
  int height_;
  std::vector<unsigned char> buffer_;  // the default framebuffer's colour, RGBA8
  OSMesaContext context_ = nullptr;
};

}  // namespace

std::unique_ptr<GlContext> create_osmesa_context(int width, int height) {
  return std::make_unique<OsMesaContext>(width, height);
}

}  // namespace cellbake
