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

// "EGL_BAD_MATCH (0x3009)" for an eglGetError() code.
std::string egl_error_text(EGLint code);

}  // namespace cellbake
