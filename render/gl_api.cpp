#include "render/gl_api.h"

#include <dlfcn.h>

#include <cstdio>
#include <cstring>

#include "render/render_error.h"

namespace fp::render::gl {

#define FP_GL11_DEFINE(name) decltype(p_##name) p_##name = nullptr;
FP_GL11_FUNCTIONS(FP_GL11_DEFINE)
#undef FP_GL11_DEFINE

namespace {

// The provider of the current context. Process-wide, like the GL function pointers it fills: GLEW keeps its
// pointers in globals too, so there is exactly one loaded GL per process.
ProcLoader g_loader = nullptr;

using GlxGetProc = Proc (*)(const GLubyte*);

GlxGetProc realGlxGetProcAddress() {
  static const GlxGetProc real = [] {
    void* symbol = dlsym(RTLD_NEXT, "glXGetProcAddressARB");
    GlxGetProc fn = nullptr;
    static_assert(sizeof(fn) == sizeof(symbol), "function and object pointers differ in size");
    std::memcpy(&fn, &symbol, sizeof(fn));
    return fn;
  }();
  return real;
}

}  // namespace

void loadFunctions(ProcLoader loader) {
  g_loader = loader;
  std::string missing;
#define FP_GL11_LOAD(name)                                        \
  p_##name = reinterpret_cast<decltype(p_##name)>(loader(#name)); \
  if (!p_##name)                                                  \
    missing += std::string(missing.empty() ? "" : ", ") + #name;
  FP_GL11_FUNCTIONS(FP_GL11_LOAD)
#undef FP_GL11_LOAD
  if (!missing.empty())
    throw RenderError("the GL context lacks " + missing);
  glewExperimental = GL_TRUE;
  // glewInit loads the core and extension functions, then the GLX ones: with no GLX display (OSMesa, EGL) it
  // returns GLEW_ERROR_NO_GLX_DISPLAY after the part that matters here has succeeded.
  const GLenum status = glewInit();
  if (status != GLEW_OK && status != GLEW_ERROR_NO_GLX_DISPLAY) {
    throw RenderError(std::string("glewInit failed: ") +
                      reinterpret_cast<const char*>(glewGetErrorString(status)));
  }
  if (!GLEW_VERSION_3_3 || !glCreateShader || !glGenFramebuffers || !glDrawArraysInstanced ||
      !glVertexAttribDivisor) {
    const GLubyte* version = glGetString(GL_VERSION);
    throw RenderError(std::string("OpenGL 3.3 core or newer is needed, the context has ") +
                      (version ? reinterpret_cast<const char*>(version) : "no version"));
  }
  glGetError();  // GLEW's glGetString(GL_EXTENSIONS) probe leaves GL_INVALID_ENUM on core profiles
}

std::string versionString() {
  auto str = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_VERSION) + ", " + str(GL_RENDERER);
}

void checkError(const char* where) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof(code), "0x%04x", error);
    throw RenderError(std::string("GL error ") + code + " in " + where);
  }
}

}  // namespace fp::render::gl

// GLEW looks functions up through glXGetProcAddressARB. Defining it here, in the executable, interposes on
// libGL's: with an OSMesa or EGL context loaded it asks that context's provider, otherwise it forwards to the
// real GLX lookup (a desktop window), so GLFW and GLX keep working.
extern "C" __attribute__((visibility("default"))) fp::render::gl::Proc glXGetProcAddressARB(
    const GLubyte* name) {
  using namespace fp::render::gl;
  // GLX's own functions (GLEW probes them after the GL ones) always come from the real libGL
  const bool glx = std::strncmp(reinterpret_cast<const char*>(name), "glX", 3) == 0;
  if (g_loader && !glx)
    return g_loader(reinterpret_cast<const char*>(name));
  const GlxGetProc real = realGlxGetProcAddress();
  return real ? real(name) : nullptr;
}
