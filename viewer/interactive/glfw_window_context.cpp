#include "viewer/interactive/glfw_window_context.h"

#define GLFW_INCLUDE_NONE  // GL types come from GL/glcorearb.h (stages/render/gl_functions.h)
#include <GLFW/glfw3.h>

#include <stdexcept>

namespace cellbake {

GlfwWindowContext::GlfwWindowContext(GLFWwindow* window) : window_(window) {
  if (!window_) throw std::invalid_argument("glfw_window_context: null window");
}

void GlfwWindowContext::make_current() {
  if (glfwGetCurrentContext() != window_) glfwMakeContextCurrent(window_);
  if (glfwGetCurrentContext() != window_) throw std::runtime_error("gl_context(glfw): glfwMakeContextCurrent failed");
}

void GlfwWindowContext::release_current() {
  if (is_current()) glfwMakeContextCurrent(nullptr);
}

bool GlfwWindowContext::is_current() const { return glfwGetCurrentContext() == window_; }

GlProc GlfwWindowContext::get_proc_address(const char* name) const {
  return reinterpret_cast<GlProc>(glfwGetProcAddress(name));
}

int GlfwWindowContext::width() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return w;
}

int GlfwWindowContext::height() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return h;
}

}  // namespace cellbake
