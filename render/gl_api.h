#pragma once
/// The OpenGL API of the renderer: GLEW for everything past 1.1, and function pointers for the 1.0/1.1 entry
/// points, all resolved through one loader that the context back-end provides (OSMesa, EGL or a window).
///
/// Why not plain GLEW: Debian's GLEW is built for GLX and looks every function up through
/// glXGetProcAddressARB, and the 1.1 functions (glClear, glReadPixels, ...) are direct calls into whichever
/// libGL the linker bound. Under OSMesa those go to glvnd and do nothing; on a GPU's EGL they must not go to
/// OSMesa. Routing both through the context's own GetProcAddress makes every call reach the current context,
/// whatever the link order. Include this header, never GL/glew.h directly, in the renderer.

#include <GL/glew.h>

#include <string>

namespace fp::render::gl {

/// a GL entry point as returned by OSMesaGetProcAddress, eglGetProcAddress or glfwGetProcAddress
using Proc = void (*)();
/// looks up a GL function by name in the current context's provider; null when missing
using ProcLoader = Proc (*)(const char* name);

/// Loads every GL function through `loader` (GLEW included); a context must be current. Throws RenderError
/// when the context lacks OpenGL 3.3 core or a required function.
void loadFunctions(ProcLoader loader);

/// libGL's own glXGetProcAddressARB (never the process-wide replacement of render/gl_api.cpp): the loader of
/// a GLX context; null when libGL is not loaded
Proc glxProcAddress(const char* name);

/// "4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)"
std::string versionString();

/// Throws RenderError naming `where` when glGetError reports an error.
void checkError(const char* where);

// GL 1.0 and 1.1 entry points used by the renderer and the ImGui back-end, as pointers filled by
// loadFunctions.
#define FP_GL11_FUNCTIONS(X) \
  X(glBindTexture)           \
  X(glBlendFunc)             \
  X(glClear)                 \
  X(glClearColor)            \
  X(glClearDepth)            \
  X(glColorMask)             \
  X(glCullFace)              \
  X(glDeleteTextures)        \
  X(glDepthFunc)             \
  X(glDepthMask)             \
  X(glDisable)               \
  X(glDrawArrays)            \
  X(glDrawElements)          \
  X(glEnable)                \
  X(glFinish)                \
  X(glGenTextures)           \
  X(glGetError)              \
  X(glGetFloatv)             \
  X(glGetIntegerv)           \
  X(glGetString)             \
  X(glIsEnabled)             \
  X(glPixelStorei)           \
  X(glPolygonMode)           \
  X(glPolygonOffset)         \
  X(glReadBuffer)            \
  X(glReadPixels)            \
  X(glScissor)               \
  X(glTexImage2D)            \
  X(glTexParameteri)         \
  X(glViewport)

#define FP_GL11_DECLARE(name) extern decltype(&::name) p_##name;
FP_GL11_FUNCTIONS(FP_GL11_DECLARE)
#undef FP_GL11_DECLARE

}  // namespace fp::render::gl

// Calls of the 1.1 functions go through the loaded pointers, the way GLEW routes the newer ones.
#define glBindTexture ::fp::render::gl::p_glBindTexture
#define glBlendFunc ::fp::render::gl::p_glBlendFunc
#define glClear ::fp::render::gl::p_glClear
#define glClearColor ::fp::render::gl::p_glClearColor
#define glClearDepth ::fp::render::gl::p_glClearDepth
#define glColorMask ::fp::render::gl::p_glColorMask
#define glCullFace ::fp::render::gl::p_glCullFace
#define glDeleteTextures ::fp::render::gl::p_glDeleteTextures
#define glDepthFunc ::fp::render::gl::p_glDepthFunc
#define glDepthMask ::fp::render::gl::p_glDepthMask
#define glDisable ::fp::render::gl::p_glDisable
#define glDrawArrays ::fp::render::gl::p_glDrawArrays
#define glDrawElements ::fp::render::gl::p_glDrawElements
#define glEnable ::fp::render::gl::p_glEnable
#define glFinish ::fp::render::gl::p_glFinish
#define glGenTextures ::fp::render::gl::p_glGenTextures
#define glGetError ::fp::render::gl::p_glGetError
#define glGetFloatv ::fp::render::gl::p_glGetFloatv
#define glGetIntegerv ::fp::render::gl::p_glGetIntegerv
#define glGetString ::fp::render::gl::p_glGetString
#define glIsEnabled ::fp::render::gl::p_glIsEnabled
#define glPixelStorei ::fp::render::gl::p_glPixelStorei
#define glPolygonMode ::fp::render::gl::p_glPolygonMode
#define glPolygonOffset ::fp::render::gl::p_glPolygonOffset
#define glReadBuffer ::fp::render::gl::p_glReadBuffer
#define glReadPixels ::fp::render::gl::p_glReadPixels
#define glScissor ::fp::render::gl::p_glScissor
#define glTexImage2D ::fp::render::gl::p_glTexImage2D
#define glTexParameteri ::fp::render::gl::p_glTexParameteri
#define glViewport ::fp::render::gl::p_glViewport
