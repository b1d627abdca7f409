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
  // libGL's definition: the next one after this executable's, or libGL itself when the executable does not
  // link it (an OpenXR runtime may be what loads it)
  static const GlxGetProc real = [] {
    void* symbol = dlsym(RTLD_NEXT, "glXGetProcAddressARB");
    if (!symbol) {
      if (void* libgl = dlopen("libGL.so.1", RTLD_LAZY | RTLD_LOCAL))
        symbol = dlsym(libgl, "glXGetProcAddressARB");
    }
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

namespace fp::render::gl {

Proc glxProcAddress(const char* name) {
  const GlxGetProc real = realGlxGetProcAddress();
  return real ? real(reinterpret_cast<const GLubyte*>(name)) : nullptr;
}

namespace {

/// true when `caller` (a return address) lies in the module that holds GLEW's code: the shared libGLEW, or
/// the executable when GLEW is linked statically
bool calledFromGlew(const void* caller) {
  static const void* glewModule = [] {
    Dl_info info{};
    void* init = dlsym(RTLD_DEFAULT, "glewInit");
    return init && dladdr(init, &info) ? info.dli_fbase : nullptr;
  }();
  Dl_info info{};
  return glewModule && dladdr(caller, &info) && info.dli_fbase == glewModule;
}

}  // namespace
}  // namespace fp::render::gl

// GLEW looks functions up through glXGetProcAddressARB. Defining it here, in the executable, interposes on
// libGL's for the whole process, so only GLEW's own lookups are answered by the loaded context's provider
// (OSMesa, EGL): every other caller (an OpenXR runtime creating swapchain textures in the app's GLX context,
// a driver, a library) gets libGL's real GLX lookup, as it would without this definition. GLX's own functions
// always come from libGL.
extern "C" __attribute__((visibility("default"))) fp::render::gl::Proc glXGetProcAddressARB(
    const GLubyte* name) {
  using namespace fp::render::gl;
  const void* caller = __builtin_extract_return_addr(__builtin_return_address(0));
  const bool glx = std::strncmp(reinterpret_cast<const char*>(name), "glX", 3) == 0;
  if (g_loader && !glx && calledFromGlew(caller))
    return g_loader(reinterpret_cast<const char*>(name));
  const GlxGetProc real = realGlxGetProcAddress();
  return real ? real(name) : nullptr;
}
