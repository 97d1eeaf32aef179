#include "stages/render/gl_functions.h"

#include <array>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

bool has_extension(const GlFunctions& gl, const char* name) {
  GLint count = 0;
  gl.GetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const auto* ext = reinterpret_cast<const char*>(gl.GetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
    if (ext && std::strcmp(ext, name) == 0) return true;
  }
  return false;
}

}  // namespace

GlFunctions load_gl_functions(const GlContext& context) {
  GlFunctions gl;
#define CELLBAKE_GL_LOAD(type, member, name)                                                          \
  gl.member = reinterpret_cast<type>(context.get_proc_address(name));                                \
  if (!gl.member)                                                                                      \
    throw std::runtime_error(std::string("gl_functions(") + context.backend_name() + "): missing " + \
                             name);
  CELLBAKE_GL_REQUIRED_FUNCTIONS(CELLBAKE_GL_LOAD)
#undef CELLBAKE_GL_LOAD

  GLint major = 0, minor = 0;
  gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl.GetIntegerv(GL_MINOR_VERSION, &minor);
  if (major < 3 || (major == 3 && minor < 3))
    throw std::runtime_error("gl_functions(" + context.backend_name() + "): OpenGL 3.3 needed, context has " +
                             std::to_string(major) + "." + std::to_string(minor));
  if (major > 4 || (major == 4 && minor >= 5) || has_extension(gl, "GL_ARB_clip_control"))
    gl.ClipControl = reinterpret_cast<PFNGLCLIPCONTROLPROC>(context.get_proc_address("glClipControl"));
  if (major > 4 || (major == 4 && minor >= 3))
    gl.MemoryBarrier = reinterpret_cast<PFNGLMEMORYBARRIERPROC>(context.get_proc_address("glMemoryBarrier"));
  check_gl_error(gl, "load_gl_functions");
  return gl;
}

void check_gl_error(const GlFunctions& gl, const char* what) {
  GLenum first = GL_NO_ERROR;
  for (int i = 0; i < 16; ++i) {  // bounded: a lost context may report errors forever
    const GLenum e = gl.GetError();
    if (e == GL_NO_ERROR) break;
    if (first == GL_NO_ERROR) first = e;
  }
  if (first == GL_NO_ERROR) return;
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", first);
  throw std::runtime_error(std::string("GL error ") + code + " in " + what);
}

namespace {

GLuint compile_shader(const GlFunctions& gl, GLenum type, const char* source, const char* who) {
  const GLuint shader = gl.CreateShader(type);
  gl.ShaderSource(shader, 1, &source, nullptr);
  gl.CompileShader(shader);
  GLint ok = GL_FALSE;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::array<char, 4096> log{};
    gl.GetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
    gl.DeleteShader(shader);
    throw std::runtime_error(std::string(who) + ": " + (type == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                             " shader failed to compile: " + log.data());
  }
  return shader;
}

}  // namespace

GLuint build_gl_program(const GlFunctions& gl, const char* vertex_source, const char* fragment_source,
                        const char* who) {
  const GLuint vs = compile_shader(gl, GL_VERTEX_SHADER, vertex_source, who);
  GLuint fs = 0;
  try {
    fs = compile_shader(gl, GL_FRAGMENT_SHADER, fragment_source, who);
  } catch (...) {
    gl.DeleteShader(vs);
    throw;
  }
  const GLuint program = gl.CreateProgram();
  gl.AttachShader(program, vs);
  gl.AttachShader(program, fs);
  gl.LinkProgram(program);
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint ok = GL_FALSE;
  gl.GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::array<char, 4096> log{};
    gl.GetProgramInfoLog(program, static_cast<GLsizei>(log.size()), nullptr, log.data());
    gl.DeleteProgram(program);
    throw std::runtime_error(std::string(who) + ": shader program failed to link: " + log.data());
  }
  return program;
}

}  // namespace cellbake
