#include "tests/xr/xr_test_env.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fp::test {

std::string useTestRuntime(const std::string& dir) {
  std::filesystem::create_directories(dir);
  for (const char* name :
       {"FP_XR_NO_GL", "FP_XR_NO_HANDS", "FP_XR_NO_HMD", "FP_XR_NO_STAGE", "FP_XR_VIRTUAL_TIME",
        "FP_XR_PERIOD_NS", "FP_XR_SIZE", "FP_XR_FORMATS", "FP_XR_HEAD", "FP_XR_IPD", "FP_XR_HANDS_OFFSET",
        "FP_XR_CONTROLLERS", "FP_XR_HANDS", "FP_XR_EVENTS", "FP_XR_STATS", "FP_XR_FRAME_LOG", "FP_XR_CAPTURE",
        "FP_XR_PROFILE", "FP_XR_FRAME_HASH"})
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
  engine::GlWindowOptions options;
  options.width = 64;
  options.height = 64;
  options.visible = false;
  options.title = "FluidPlaying XR test";
  options.swapInterval = 0;
  try {
    m_window = std::make_unique<engine::GlWindow>(options);
  } catch (const std::exception& e) {  // WindowUnavailable, render::RenderError
    error = e.what();
    return false;
  }
  const engine::GlxBinding b = m_window->glxBinding();
  display = static_cast<Display*>(b.display);
  config = static_cast<GLXFBConfig>(b.fbConfig);
  drawable = GLXDrawable(b.drawable);
  context = static_cast<GLXContext>(b.context);
  if (!display || !context) {
    error = "the window's context is not a GLX one";
    return false;
  }
  return true;
}

}  // namespace fp::test
