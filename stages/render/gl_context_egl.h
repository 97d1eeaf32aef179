// EGL backend of GlContext: an OpenGL core profile context (the highest of
// 4.6 down to 3.3) without any surface (EGL_KHR_surfaceless_context); drawing
// goes to framebuffer objects. Needs no window system, no environment
// variables and no OSMesa.
//
// Display selection (egl_display.h has the details):
//   prefer_hardware: the first enumerated EGL device (EGL_EXT_device_enumeration
//     + EGL_EXT_platform_device) whose extensions do not include
//     EGL_MESA_device_software and which initialises; else Mesa's surfaceless
//     platform (EGL_MESA_platform_surfaceless); else the software device.
//   software_only: the software device (EGL_MESA_device_software, llvmpipe);
//     else Mesa's surfaceless platform (Mesa may pick a hardware driver there).
//   hardware_only: the first hardware device that initialises, else an error
//     (what `sample.backend = "auto"` probes before it picks EGL).
//
// Threads: release_current() (and destruction, and a failed creation) also
// hands the calling thread's EGL state back with eglReleaseThread when no EGL
// context stays current there, so pool threads that outlive exit()'s library
// teardown hold none (egl_display.h, release_idle_egl_thread).
#pragma once

#include <memory>
#include <string>

#include "stages/render/gl_context.h"

namespace cellbake {

enum class EglDevicePolicy { prefer_hardware, software_only, hardware_only };

// An EGL context of `width` x `height` nominal pixels (both >= 1; there is no
// default framebuffer, width()/height() report the request), current on the
// calling thread. backend_name() is "egl". Throws std::invalid_argument for
// bad sizes and std::runtime_error naming "egl", the display tried and the
// EGL error code when no context can be created.
std::unique_ptr<GlContext> create_egl_context(int width, int height,
                                              EglDevicePolicy policy = EglDevicePolicy::prefer_hardware);

// True when EGL enumerates a device that is not Mesa's software device (a GPU).
// Initialises nothing and creates no context.
bool egl_hardware_device_present();

// "" when an EGL context can be created on a hardware device, else why not
// (the error, naming each device tried). Probes by creating and destroying a
// 1x1 hardware_only context on a short-lived thread of its own, so the calling
// thread's current context is untouched; costs a context creation.
std::string egl_hardware_context_error();

}  // namespace cellbake
