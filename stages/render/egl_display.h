// Chooses and initialises the EGL display a GlContext runs on (the selection
// rule of gl_context_egl.h). Internal to stages/render.
#pragma once

#include <EGL/egl.h>

#include <string>

#include "stages/render/gl_context_egl.h"

namespace cellbake {

struct EglDisplayChoice {
  EGLDisplay display = EGL_NO_DISPLAY;  // initialised
  std::string description;              // e.g. "device 1 (/dev/dri/renderD128)", "surfaceless"
};

// The display `policy` selects, initialised. Displays are never terminated:
// eglTerminate would also destroy other contexts on the same display (EGL
// displays are per process, not reference counted without
// EGL_KHR_display_reference), so an initialised display lives as long as the
// process. Throws std::runtime_error naming "egl", each candidate tried and
// its EGL error code when none initialises.
EglDisplayChoice open_egl_display(EglDevicePolicy policy);

// The number of EGL devices that are not Mesa's software device.
int egl_hardware_device_count();

// Hands the calling thread's EGL state back (eglReleaseThread) when no EGL
// context is current on it; does nothing while one is. Every EGL call may
// allocate that per-thread state, and libglvnd's libEGL keeps it behind a
// pthread key whose destructor frees it when the thread ends. At exit()
// libEGL's library destructor frees every thread's state but leaves those
// key values in place, so a thread that still holds state and ends during
// exit() (oneTBB's workers do) frees it a second time: heap corruption after
// the work is done. A thread that is done with EGL calls this last; EGL
// allocates the state again on its next call.
void release_idle_egl_thread();

// "EGL_BAD_MATCH (0x3009)" for an eglGetError() code.
std::string egl_error_text(EGLint code);

}  // namespace cellbake
