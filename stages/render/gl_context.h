// An offscreen OpenGL context behind one small backend interface, so the
// sampler and the headless viewer run on any machine: OSMesa (Mesa's software
// rasteriser into host memory) or EGL (a GPU device when one is present, else
// Mesa's surfaceless platform, llvmpipe), without touching the drawing code.
//
// A context is current on at most one thread at a time; use one context per
// thread. Nothing here changes global state beyond the calling thread's
// current context, and nothing reads or sets environment variables (llvmpipe's
// thread count, LP_NUM_THREADS, is the caller's business).
#pragma once

#include <memory>
#include <optional>
#include <string>

namespace cellbake {

// Any GL entry point, as returned by a backend's get-proc-address.
using GlProc = void (*)();

enum class GlBackend {
  osmesa,  // Mesa's OSMesa (llvmpipe): a 3.3+ core profile context into a host-memory buffer
  egl,     // EGL without a surface: first hardware device, else Mesa surfaceless (gl_context_egl.h)
};

// "osmesa" | "egl".
std::string gl_backend_name(GlBackend backend);

class GlContext {
 public:
  virtual ~GlContext() = default;
  // Makes this context current on the calling thread. Throws std::runtime_error
  // naming the backend when that fails.
  virtual void make_current() = 0;
  // Leaves the calling thread with no current context when this one is current
  // there. Call it before another thread may destroy or use the context: a
  // context destroyed while still current on some thread leaves that thread's
  // driver state dangling.
  virtual void release_current() = 0;
  // True when this context is the calling thread's current context.
  virtual bool is_current() const = 0;
  // The entry point `name` (e.g. "glClipControl"), or nullptr when the
  // implementation does not provide it. Needs no current context.
  virtual GlProc get_proc_address(const char* name) const = 0;
  // Width and height in pixels of the context's default framebuffer (drawing
  // normally goes to framebuffer objects of any size instead; a backend
  // without a default framebuffer reports the requested size).
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Backend name, e.g. "osmesa".
  virtual std::string backend_name() const = 0;
};

// Creates an offscreen OpenGL 3.3+ core profile context whose default
// framebuffer is `width` x `height` pixels (both >= 1), and makes it current
// on the calling thread. Throws std::invalid_argument for bad sizes and
// std::runtime_error naming the backend when the context cannot be created
// (including a build without that backend: see gl_backend_compiled).
std::unique_ptr<GlContext> create_gl_context(GlBackend backend, int width, int height);

// True when this build includes `backend` (OSMesa is optional at build time,
// CMake option CELLBAKE_WITH_OSMESA; EGL is always built).
bool gl_backend_compiled(GlBackend backend);

// True when a context of `backend` can be created here. Probes by creating
// and destroying a 1x1 context on a short-lived thread of its own, so the
// calling thread's current context is untouched. Costs a context creation
// (milliseconds on llvmpipe); call it once, not per frame.
bool gl_backend_available(GlBackend backend);

// The headless fallback order: OSMesa when available, else EGL; nullopt when
// neither can create a context.
std::optional<GlBackend> first_available_gl_backend();

// create_gl_context with the fallback order above, in one step and without a
// probe: OSMesa when it creates a context, else EGL. Throws std::runtime_error
// quoting both backends' errors when neither does.
std::unique_ptr<GlContext> create_headless_gl_context(int width, int height);

}  // namespace cellbake
