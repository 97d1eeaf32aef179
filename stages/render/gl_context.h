// An offscreen OpenGL context behind one small backend interface, so the
// sampler and the headless viewer run on any machine (OSMesa, Mesa's software
// rasteriser) and a second backend (EGL surfaceless, or a GPU) can be added
// beside it without touching the drawing code.
//
// A context is current on at most one thread at a time; use one context per
// thread. Nothing here changes global state beyond the calling thread's
// current context, and nothing reads or sets environment variables (OSMesa's
// llvmpipe thread count, LP_NUM_THREADS, is the caller's business).
#pragma once

#include <memory>
#include <string>

namespace cellbake {

// Any GL entry point, as returned by a backend's get-proc-address.
using GlProc = void (*)();

enum class GlBackend {
  osmesa,  // Mesa's OSMesa (llvmpipe): a 3.3+ core profile context into a host-memory buffer
};

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
  // normally goes to framebuffer objects of any size instead).
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Backend name, e.g. "osmesa".
  virtual std::string backend_name() const = 0;
};

// Creates an offscreen OpenGL 3.3+ core profile context whose default
// framebuffer is `width` x `height` pixels (both >= 1), and makes it current
// on the calling thread. Throws std::invalid_argument for bad sizes and
// std::runtime_error naming the backend when the context cannot be created.
std::unique_ptr<GlContext> create_gl_context(GlBackend backend, int width, int height);

}  // namespace cellbake
