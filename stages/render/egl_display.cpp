#include "stages/render/egl_display.h"

#include <EGL/eglext.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace cellbake {
namespace {

// True when the space-separated extension list `list` contains `name` exactly.
bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

const char* client_extensions() { return eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS); }

struct DeviceApi {
  PFNEGLQUERYDEVICESEXTPROC query_devices = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC query_device_string = nullptr;
};

// The device-enumeration entry points, or nulls when EGL lacks them.
DeviceApi device_api() {
  DeviceApi api;
  const char* ext = client_extensions();
  if (!has_extension(ext, "EGL_EXT_device_enumeration") && !has_extension(ext, "EGL_EXT_device_base")) return api;
  api.query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  api.query_device_string =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
  return api;
}

struct Device {
  EGLDeviceEXT handle;
  int index;
  bool software;
  std::string description;
};

std::vector<Device> enumerate_devices() {
  const DeviceApi api = device_api();
  if (!api.query_devices || !api.query_device_string) return {};
  EGLint count = 0;
  if (!api.query_devices(0, nullptr, &count) || count <= 0) return {};
  std::vector<EGLDeviceEXT> handles(static_cast<std::size_t>(count));
  if (!api.query_devices(count, handles.data(), &count)) return {};
  std::vector<Device> devices;
  for (EGLint i = 0; i < count; ++i) {
    const char* ext = api.query_device_string(handles[i], EGL_EXTENSIONS);
    Device d{handles[i], i, has_extension(ext, "EGL_MESA_device_software"), "device " + std::to_string(i)};
    const char* file = has_extension(ext, "EGL_EXT_device_drm") ? api.query_device_string(handles[i], EGL_DRM_DEVICE_FILE_EXT)
                                                                 : nullptr;
    if (d.software) d.description += " (Mesa software)";
    else if (file) d.description += std::string(" (") + file + ")";
    devices.push_back(std::move(d));
  }
  return devices;
}

// Initialises `display`; on failure appends "<what>: <error>" to `tried`.
bool initialise(EGLDisplay display, const std::string& what, std::string& tried) {
  if (display == EGL_NO_DISPLAY) {
    tried += "\n  " + what + ": eglGetPlatformDisplay failed, " + egl_error_text(eglGetError());
    return false;
  }
  EGLint major = 0, minor = 0;
  if (eglInitialize(display, &major, &minor)) return true;
  tried += "\n  " + what + ": eglInitialize failed, " + egl_error_text(eglGetError());
  return false;
}

bool try_device(const Device& d, EglDisplayChoice& out, std::string& tried) {
  if (!has_extension(client_extensions(), "EGL_EXT_platform_device")) {
    tried += "\n  " + d.description + ": no EGL_EXT_platform_device";
    return false;
  }
  EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, d.handle, nullptr);
  if (!initialise(display, d.description, tried)) return false;
  out = {display, d.description};
  return true;
}

bool try_surfaceless(EglDisplayChoice& out, std::string& tried) {
  if (!has_extension(client_extensions(), "EGL_MESA_platform_surfaceless")) {
    tried += "\n  surfaceless: no EGL_MESA_platform_surfaceless";
    return false;
  }
  EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (!initialise(display, "surfaceless", tried)) return false;
  out = {display, "surfaceless"};
  return true;
}

}  // namespace

std::string egl_error_text(EGLint code) {
  const char* name = "unknown EGL error";
  switch (code) {
    case EGL_SUCCESS: name = "EGL_SUCCESS"; break;
    case EGL_NOT_INITIALIZED: name = "EGL_NOT_INITIALIZED"; break;
    case EGL_BAD_ACCESS: name = "EGL_BAD_ACCESS"; break;
    case EGL_BAD_ALLOC: name = "EGL_BAD_ALLOC"; break;
    case EGL_BAD_ATTRIBUTE: name = "EGL_BAD_ATTRIBUTE"; break;
    case EGL_BAD_CONFIG: name = "EGL_BAD_CONFIG"; break;
    case EGL_BAD_CONTEXT: name = "EGL_BAD_CONTEXT"; break;
    case EGL_BAD_CURRENT_SURFACE: name = "EGL_BAD_CURRENT_SURFACE"; break;
    case EGL_BAD_DISPLAY: name = "EGL_BAD_DISPLAY"; break;
    case EGL_BAD_MATCH: name = "EGL_BAD_MATCH"; break;
    case EGL_BAD_NATIVE_PIXMAP: name = "EGL_BAD_NATIVE_PIXMAP"; break;
    case EGL_BAD_NATIVE_WINDOW: name = "EGL_BAD_NATIVE_WINDOW"; break;
    case EGL_BAD_PARAMETER: name = "EGL_BAD_PARAMETER"; break;
    case EGL_BAD_SURFACE: name = "EGL_BAD_SURFACE"; break;
    case EGL_CONTEXT_LOST: name = "EGL_CONTEXT_LOST"; break;
    default: break;
  }
  char code_text[16];
  std::snprintf(code_text, sizeof code_text, "0x%04x", static_cast<unsigned>(code));
  return std::string(name) + " (" + code_text + ")";
}

void release_idle_egl_thread() {
  if (eglGetCurrentContext() == EGL_NO_CONTEXT) eglReleaseThread();
}

int egl_hardware_device_count() {
  int n = 0;
  for (const Device& d : enumerate_devices()) n += d.software ? 0 : 1;
  release_idle_egl_thread();  // the probe may run on a pool thread
  return n;
}

EglDisplayChoice open_egl_display(EglDevicePolicy policy) {
  const std::vector<Device> devices = enumerate_devices();
  EglDisplayChoice choice;
  std::string tried;
  if (policy == EglDevicePolicy::prefer_hardware || policy == EglDevicePolicy::hardware_only)
    for (const Device& d : devices)
      if (!d.software && try_device(d, choice, tried)) return choice;
  if (policy == EglDevicePolicy::hardware_only)
    throw std::runtime_error("gl_context(egl): no hardware EGL device could be initialised; tried:" +
                             (tried.empty() ? std::string(" nothing (no hardware devices)") : tried));
  const auto try_software_devices = [&] {
    for (const Device& d : devices)
      if (d.software && try_device(d, choice, tried)) return true;
    return false;
  };
  if (policy == EglDevicePolicy::software_only && try_software_devices()) return choice;
  if (try_surfaceless(choice, tried)) return choice;
  if (policy == EglDevicePolicy::prefer_hardware && try_software_devices()) return choice;
  throw std::runtime_error("gl_context(egl): no EGL display could be initialised; tried:" +
                           (tried.empty() ? std::string(" nothing (no devices, no surfaceless platform)") : tried));
}

}  // namespace cellbake
