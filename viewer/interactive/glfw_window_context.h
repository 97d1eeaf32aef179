// GlContext over a GLFW window's OpenGL context, so that the offscreen drawing
// code (ChunkRenderer, TdmRenderer, SceneDrawer) runs unchanged in the
// interactive viewer: entry points come from glfwGetProcAddress.
#pragma once

#include <string>

#include "stages/render/gl_context.h"

struct GLFWwindow;

namespace cellbake {

// Does not own the window; the window must outlive every user of the context.
class GlfwWindowContext final : public GlContext {
 public:
  explicit GlfwWindowContext(GLFWwindow* window);
  void make_current() override;
  void release_current() override;
  bool is_current() const override;
  GlProc get_proc_address(const char* name) const override;
  int width() const override;
  int height() const override;
  std::string backend_name() const override { return "glfw"; }

 private:
  GLFWwindow* window_;
};

}  // namespace cellbake
