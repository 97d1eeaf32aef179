// The OpenGL entry points the renderer uses, fetched through a GlContext's
// get-proc-address (libOSMesa does not export most GL 3+/4.x symbols, and we
// link no libGL). One table per context; call through it only while that
// context is current.
#pragma once

#include <GL/glcorearb.h>

#include "stages/render/gl_context.h"

namespace cellbake {

// X(typedef, member, "glName"): every required entry point.
#define CELLBAKE_GL_REQUIRED_FUNCTIONS(X)                                               \
  X(PFNGLGETERRORPROC, GetError, "glGetError")                                          \
  X(PFNGLGETSTRINGPROC, GetString, "glGetString")                                       \
  X(PFNGLGETSTRINGIPROC, GetStringi, "glGetStringi")                                    \
  X(PFNGLGETINTEGERVPROC, GetIntegerv, "glGetIntegerv")                                 \
  X(PFNGLENABLEPROC, Enable, "glEnable")                                                \
  X(PFNGLDISABLEPROC, Disable, "glDisable")                                             \
  X(PFNGLVIEWPORTPROC, Viewport, "glViewport")                                          \
  X(PFNGLDEPTHFUNCPROC, DepthFunc, "glDepthFunc")                                       \
  X(PFNGLDEPTHMASKPROC, DepthMask, "glDepthMask")                                       \
  X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv, "glClearBufferfv")                           \
  X(PFNGLCLEARBUFFERUIVPROC, ClearBufferuiv, "glClearBufferuiv")                        \
  X(PFNGLFINISHPROC, Finish, "glFinish")                                                \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers, "glGenFramebuffers")                     \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers, "glDeleteFramebuffers")            \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer, "glBindFramebuffer")                     \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus, "glCheckFramebufferStatus") \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer, "glFramebufferRenderbuffer") \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers, "glGenRenderbuffers")                  \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers, "glDeleteRenderbuffers")         \
  X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer, "glBindRenderbuffer")                  \
  X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage, "glRenderbufferStorage")         \
  X(PFNGLDRAWBUFFERSPROC, DrawBuffers, "glDrawBuffers")                                 \
  X(PFNGLREADBUFFERPROC, ReadBuffer, "glReadBuffer")                                    \
  X(PFNGLPIXELSTOREIPROC, PixelStorei, "glPixelStorei")                                 \
  X(PFNGLREADPIXELSPROC, ReadPixels, "glReadPixels")                                    \
  X(PFNGLCREATESHADERPROC, CreateShader, "glCreateShader")                              \
  X(PFNGLSHADERSOURCEPROC, ShaderSource, "glShaderSource")                              \
  X(PFNGLCOMPILESHADERPROC, CompileShader, "glCompileShader")                           \
  X(PFNGLGETSHADERIVPROC, GetShaderiv, "glGetShaderiv")                                 \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog, "glGetShaderInfoLog")                  \
  X(PFNGLDELETESHADERPROC, DeleteShader, "glDeleteShader")                              \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram, "glCreateProgram")                           \
  X(PFNGLATTACHSHADERPROC, AttachShader, "glAttachShader")                              \
  X(PFNGLLINKPROGRAMPROC, LinkProgram, "glLinkProgram")                                 \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv, "glGetProgramiv")                              \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog, "glGetProgramInfoLog")               \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram, "glDeleteProgram")                           \
  X(PFNGLUSEPROGRAMPROC, UseProgram, "glUseProgram")                                    \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation, "glGetUniformLocation")            \
  X(PFNGLUNIFORM3FPROC, Uniform3f, "glUniform3f")                                       \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv, "glUniformMatrix4fv")                  \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays, "glGenVertexArrays")                     \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays, "glDeleteVertexArrays")            \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray, "glBindVertexArray")                     \
  X(PFNGLGENBUFFERSPROC, GenBuffers, "glGenBuffers")                                    \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers, "glDeleteBuffers")                           \
  X(PFNGLBINDBUFFERPROC, BindBuffer, "glBindBuffer")                                    \
  X(PFNGLBUFFERDATAPROC, BufferData, "glBufferData")                                    \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray, "glEnableVertexAttribArray") \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer, "glVertexAttribPointer")         \
  X(PFNGLDRAWELEMENTSPROC, DrawElements, "glDrawElements")                             \
  X(PFNGLUNIFORM1IPROC, Uniform1i, "glUniform1i")                                       \
  X(PFNGLUNIFORM1FPROC, Uniform1f, "glUniform1f")                                       \
  X(PFNGLUNIFORM4FPROC, Uniform4f, "glUniform4f")                                       \
  X(PFNGLGENTEXTURESPROC, GenTextures, "glGenTextures")                                 \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures, "glDeleteTextures")                        \
  X(PFNGLBINDTEXTUREPROC, BindTexture, "glBindTexture")                                 \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture, "glActiveTexture")                           \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D, "glTexImage2D")                                    \
  X(PFNGLTEXPARAMETERIPROC, TexParameteri, "glTexParameteri")                           \
  X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap, "glGenerateMipmap")                        \
  X(PFNGLPOLYGONMODEPROC, PolygonMode, "glPolygonMode")                                 \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer, "glBlitFramebuffer")                   \
  X(PFNGLCOLORMASKPROC, ColorMask, "glColorMask")                                       \
  X(PFNGLDRAWELEMENTSINSTANCEDPROC, DrawElementsInstanced, "glDrawElementsInstanced")   \
  X(PFNGLVERTEXATTRIBDIVISORPROC, VertexAttribDivisor, "glVertexAttribDivisor")         \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase, "glBindBufferBase")                        \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData, "glBufferSubData")                           \
  X(PFNGLGETBUFFERSUBDATAPROC, GetBufferSubData, "glGetBufferSubData")

struct GlFunctions {
#define CELLBAKE_GL_MEMBER(type, member, name) type member = nullptr;
  CELLBAKE_GL_REQUIRED_FUNCTIONS(CELLBAKE_GL_MEMBER)
#undef CELLBAKE_GL_MEMBER
  // Optional (GL 4.5 / GL_ARB_clip_control): nullptr when the context lacks it.
  PFNGLCLIPCONTROLPROC ClipControl = nullptr;
  // Optional (GL 4.3: shader storage buffers and early fragment tests, used by
  // ChunkRenderer's occlusion culling): nullptr when the context lacks GL 4.3.
  PFNGLMEMORYBARRIERPROC MemoryBarrier = nullptr;
};

// Fetches every entry point through `context`'s get-proc-address. Throws
// std::runtime_error naming the first missing required function. Optional
// functions are left nullptr when absent (ClipControl is kept only when the
// context reports GL 4.5+ or GL_ARB_clip_control, MemoryBarrier only on GL 4.3+;
// `context` must be current).
GlFunctions load_gl_functions(const GlContext& context);

// Throws std::runtime_error naming `what` and the GL error code when glGetError
// reports an error (the error flags are cleared either way).
void check_gl_error(const GlFunctions& gl, const char* what);

// Compiles and links a vertex + fragment shader program. Throws
// std::runtime_error("WHO: ... shader failed to compile/link: LOG") and leaves
// no GL objects behind on failure. Needs a current context.
GLuint build_gl_program(const GlFunctions& gl, const char* vertex_source, const char* fragment_source,
                        const char* who);

}  // namespace cellbake
