// EGL backend of GlContext (see gl_context_egl.h): eglBindAPI(EGL_OPENGL_API),
// a configless context when the display allows it (EGL_KHR_no_config_context),
// else the first config that renders OpenGL, and no surface.
#include "stages/render/gl_context_egl.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "stages/render/egl_display.h"

namespace cellbake {
namespace {

bool display_has_extension(EGLDisplay display, const char* name) {
  const char* list = eglQueryString(display, EGL_EXTENSIONS);
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == '\0' || p[n] == ' ')) return true;
  return false;
}

std::runtime_error egl_failure(const std::string& what, const std::string& display) {
  return std::runtime_error("gl_context(egl): " + what + " on " + display + ", " + egl_error_text(eglGetError()));
}

// EGL_NO_CONFIG_KHR when the display takes configless contexts, else a config
// that renders OpenGL (the surface type does not matter: no surface is made).
EGLConfig choose_config(EGLDisplay display, const std::string& description) {
  if (display_has_extension(display, "EGL_KHR_no_config_context") ||
      display_has_extension(display, "EGL_MESA_configless_context"))
    return EGL_NO_CONFIG_KHR;
  const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(display, attribs, &config, 1, &count)) throw egl_failure("eglChooseConfig failed", description);
  if (count < 1) throw std::runtime_error("gl_context(egl): no EGL config renders OpenGL on " + description);
  return config;
}

// The highest core profile context from 4.6 down to 3.3.
EGLContext create_core_context(EGLDisplay display, EGLConfig config, const std::string& description) {
  static constexpr std::pair<EGLint, EGLint> kVersions[] = {{4, 6}, {4, 5}, {4, 4}, {4, 3}, {4, 2},
                                                            {4, 1}, {4, 0}, {3, 3}};
  EGLint last_error = EGL_SUCCESS;
  for (const auto& [major, minor] : kVersions) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              major,
                              EGL_CONTEXT_MINOR_VERSION,
                              minor,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
    if (context != EGL_NO_CONTEXT) return context;
    last_error = eglGetError();
  }
  throw std::runtime_error("gl_context(egl): eglCreateContext failed for every OpenGL core profile 4.6..3.3 on " +
                           description + ", last " + egl_error_text(last_error));
}

class EglContext final : public GlContext {
 public:
  EglContext(int width, int height, EglDevicePolicy policy) : width_(width), height_(height) {
    EglDisplayChoice choice = open_egl_display(policy);
    display_ = choice.display;
    description_ = std::move(choice.description);
    if (!display_has_extension(display_, "EGL_KHR_surfaceless_context"))
      throw std::runtime_error("gl_context(egl): " + description_ + " lacks EGL_KHR_surfaceless_context");
    if (!eglBindAPI(EGL_OPENGL_API)) throw egl_failure("eglBindAPI(EGL_OPENGL_API) failed", description_);
    context_ = create_core_context(display_, choose_config(display_, description_), description_);
    try {
      make_current();
    } catch (...) {
      eglDestroyContext(display_, context_);
      throw;
    }
  }
  ~EglContext() override {
    if (is_current()) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    release_idle_egl_thread();
  }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // Binds the OpenGL API on the calling thread (EGL's current-context queries
  // are per API) and makes the context current without a surface. Rebinds
  // when EGL already holds it current: libglvnd skips a repeated
  // eglMakeCurrent, yet an OSMesa context made current since then owns the
  // thread's GL dispatch (both go through Mesa's libglapi).
  void make_current() override {
    if (!eglBindAPI(EGL_OPENGL_API)) throw egl_failure("eglBindAPI(EGL_OPENGL_API) failed", description_);
    if (eglGetCurrentContext() == context_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw egl_failure("eglMakeCurrent failed", description_);
  }
  // Also hands the thread's EGL state back when nothing else of EGL is current
  // on it (release_idle_egl_thread): a pool thread that releases its context
  // after each job holds no EGL state when it ends during exit().
  void release_current() override {
    if (is_current()) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    release_idle_egl_thread();
  }
  // Asks for the OpenGL API's current context, restoring the thread's bound API.
  bool is_current() const override {
    const EGLenum api = eglQueryAPI();
    if (api != EGL_OPENGL_API) eglBindAPI(EGL_OPENGL_API);
    const bool current = eglGetCurrentContext() == context_;
    if (api != EGL_OPENGL_API) eglBindAPI(api);
    return current;
  }
  GlProc get_proc_address(const char* name) const override { return eglGetProcAddress(name); }
  int width() const override { return width_; }
  int height() const override { return height_; }
  std::string backend_name() const override { return "egl"; }

 private:
  int width_;
  int height_;
  EGLDisplay display_ = EGL_NO_DISPLAY;  // initialised, never terminated (egl_display.h)
  std::string description_;              // which display, for errors
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> create_egl_context(int width, int height, EglDevicePolicy policy) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("gl_context(egl): size must be at least 1x1, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  try {
    return std::make_unique<EglContext>(width, height, policy);
  } catch (...) {
    release_idle_egl_thread();  // a failed creation leaves no EGL state on this thread either
    throw;
  }
}

bool egl_hardware_device_present() { return egl_hardware_device_count() > 0; }

std::string egl_hardware_context_error() {
  std::string error;
  std::thread probe([&] {
    try {
      create_egl_context(1, 1, EglDevicePolicy::hardware_only);  // current on the probe thread until destroyed
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  probe.join();
  return error;
}

}  // namespace cellbake
