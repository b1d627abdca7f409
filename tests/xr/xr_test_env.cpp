#include "tests/xr/xr_test_env.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "render/gl_api.h"

namespace fp::test {

std::string useTestRuntime(const std::string& dir) {
  std::filesystem::create_directories(dir);
  for (const char* name :
       {"FP_XR_NO_GL", "FP_XR_NO_HANDS", "FP_XR_NO_HMD", "FP_XR_NO_STAGE", "FP_XR_VIRTUAL_TIME",
        "FP_XR_PERIOD_NS", "FP_XR_SIZE", "FP_XR_FORMATS", "FP_XR_HEAD", "FP_XR_IPD", "FP_XR_HANDS_OFFSET",
        "FP_XR_CONTROLLERS", "FP_XR_HANDS", "FP_XR_EVENTS", "FP_XR_STATS", "FP_XR_FRAME_LOG", "FP_XR_CAPTURE",
        "FP_XR_PROFILE"})
    unsetenv(name);
  setenv("XR_RUNTIME_JSON", FP_TEST_RUNTIME_JSON, 1);
  setenv("XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation", 1);
  setenv("XR_CORE_VALIDATION_EXPORT_TYPE", "text", 1);
  const std::string file = dir + "/validation.txt";
  std::filesystem::remove(file);
  setenv("XR_CORE_VALIDATION_FILE_NAME", file.c_str(), 1);
  return file;
}

std::string validationMessages(const std::string& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

long runtimeStat(const std::string& statsFile, const std::string& key) {
  std::ifstream in(statsFile);
  std::string k;
  long v = 0;
  while (in >> k >> v) {
    if (k == key)
      return v;
  }
  return -1;
}

bool GlxContext::create(std::string& error) {
  display = XOpenDisplay(nullptr);
  if (!display) {
    error = "no X display";
    return false;
  }
  const int attributes[] = {GLX_DRAWABLE_TYPE,
                            GLX_PBUFFER_BIT | GLX_WINDOW_BIT,
                            GLX_RENDER_TYPE,
                            GLX_RGBA_BIT,
                            GLX_RED_SIZE,
                            8,
                            GLX_GREEN_SIZE,
                            8,
                            GLX_BLUE_SIZE,
                            8,
                            GLX_DEPTH_SIZE,
                            24,
                            None};
  int count = 0;
  GLXFBConfig* configs = glXChooseFBConfig(display, DefaultScreen(display), attributes, &count);
  if (!configs || count == 0) {
    error = "no GLX framebuffer configuration";
    return false;
  }
  config = configs[0];
  XFree(configs);
  using CreateContext = GLXContext (*)(Display*, GLXFBConfig, GLXContext, Bool, const int*);
  const auto createContext =
      reinterpret_cast<CreateContext>(render::gl::glxProcAddress("glXCreateContextAttribsARB"));
  const int contextAttributes[] = {
      GLX_CONTEXT_MAJOR_VERSION_ARB,    3,   GLX_CONTEXT_MINOR_VERSION_ARB, 3, GLX_CONTEXT_PROFILE_MASK_ARB,
      GLX_CONTEXT_CORE_PROFILE_BIT_ARB, None};
  context = createContext ? createContext(display, config, nullptr, True, contextAttributes) : nullptr;
  const int pbufferAttributes[] = {GLX_PBUFFER_WIDTH, 16, GLX_PBUFFER_HEIGHT, 16, None};
  pbuffer = glXCreatePbuffer(display, config, pbufferAttributes);
  if (!context || !pbuffer || !glXMakeContextCurrent(display, pbuffer, pbuffer, context)) {
    error = "no GLX 3.3 core context";
    return false;
  }
  if (loadGl)
    render::gl::loadFunctions(&render::gl::glxProcAddress);
  return true;
}

GlxContext::~GlxContext() {
  if (display) {
    glXMakeContextCurrent(display, None, None, nullptr);
    if (context)
      glXDestroyContext(display, context);
    if (pbuffer)
      glXDestroyPbuffer(display, pbuffer);
    XCloseDisplay(display);
  }
}

}  // namespace fp::test
