// The backend switch of gl_context.h: creation by name, availability probes
// and the headless fallback order (OSMesa, then EGL).
#include "stages/render/gl_context.h"

#include <exception>
#include <stdexcept>
#include <thread>

#include "stages/render/gl_context_egl.h"
#if CELLBAKE_HAVE_OSMESA
#include "stages/render/gl_context_osmesa.h"
#endif

namespace cellbake {

std::string gl_backend_name(GlBackend backend) {
  switch (backend) {
    case GlBackend::osmesa: return "osmesa";
    case GlBackend::egl: return "egl";
  }
  throw std::invalid_argument("gl_context: unknown backend");
}

bool gl_backend_compiled(GlBackend backend) {
  switch (backend) {
    case GlBackend::osmesa: return CELLBAKE_HAVE_OSMESA != 0;
    case GlBackend::egl: return true;
  }
  return false;
}

std::unique_ptr<GlContext> create_gl_context(GlBackend backend, int width, int height) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("gl_context: size must be at least 1x1, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  switch (backend) {
    case GlBackend::osmesa:
#if CELLBAKE_HAVE_OSMESA
      return create_osmesa_context(width, height);
#else
      throw std::runtime_error("gl_context(osmesa): this build has no OSMesa (CELLBAKE_WITH_OSMESA=OFF); use egl");
#endif
    case GlBackend::egl: return create_egl_context(width, height, EglDevicePolicy::prefer_hardware);
  }
  throw std::invalid_argument("gl_context: unknown backend");
}

bool gl_backend_available(GlBackend backend) {
  if (!gl_backend_compiled(backend)) return false;
  bool ok = false;
  std::thread probe([&] {
    try {
      create_gl_context(backend, 1, 1);  // created current on the probe thread, released when destroyed
      ok = true;
    } catch (const std::exception&) {
      ok = false;
    }
  });
  probe.join();
  return ok;
}

std::optional<GlBackend> first_available_gl_backend() {
  for (GlBackend backend : {GlBackend::osmesa, GlBackend::egl})
    if (gl_backend_available(backend)) return backend;
  return std::nullopt;
}

std::unique_ptr<GlContext> create_headless_gl_context(int width, int height) {
  std::string osmesa_error;
  if (gl_backend_compiled(GlBackend::osmesa)) {
    try {
      return create_gl_context(GlBackend::osmesa, width, height);
    } catch (const std::invalid_argument&) {
      throw;
    } catch (const std::exception& e) {
      osmesa_error = e.what();
    }
  } else {
    osmesa_error = "gl_context(osmesa): not in this build";
  }
  try {
    return create_gl_context(GlBackend::egl, width, height);
  } catch (const std::exception& e) {
    throw std::runtime_error("gl_context: no headless OpenGL backend: " + osmesa_error + "; " + e.what());
  }
}

}  // namespace cellbake
