#pragma once
// What every XR test shares: the test runtime selected through XR_RUNTIME_JSON, the Khronos core validation
// layer on with its messages in a file the test checks, and a GLX context on the X display (Xvfb in CI).
#include <string>

// GLEW before any GL header
#include "render/gl_api.h"

#include <GL/glx.h>
#include <X11/Xlib.h>

namespace fp::test {

/// Sets the loader's and the test runtime's environment for one test: the manifest, the validation layer
/// writing to a fresh file in `dir`, and clears every FP_XR_* variable. Returns the validation file.
std::string useTestRuntime(const std::string& dir);
/// the validation layer's messages so far ("" when there are none)
std::string validationMessages(const std::string& file);
/// the value of `key` in the runtime's statistics file (-1 when missing)
long runtimeStat(const std::string& statsFile, const std::string& key);

/// A GLX 3.3 core context on a small pbuffer, current on this thread; GL loaded through render/gl_api.
struct GlxContext {
  Display* display = nullptr;
  GLXFBConfig config = nullptr;
  GLXPbuffer pbuffer = 0;
  GLXContext context = nullptr;
  bool loadGl = true;  ///< load render/gl_api's functions from this context once it is current
  /// false (with `error`) where there is no display or no 3.3 core context
  bool create(std::string& error);
  ~GlxContext();
};

}  // namespace fp::test
