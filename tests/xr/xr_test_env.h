#pragma once
// What every XR test shares: the test runtime selected through XR_RUNTIME_JSON, the Khronos core validation
// layer on with its messages in a file the test checks, and the engine's GL context on the X display (Xvfb in
// CI).
#include <memory>
#include <string>

#include "engine/gl_window.h"

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

/// The headset mode's GL context for tests: the engine's hidden window (engine/gl_window, as `fluidplaying
/// --xr --no-window` renders in), current on this thread, GL loaded through render/gl_api, with its GLX
/// handles.
struct GlxContext {
  Display* display = nullptr;
  GLXFBConfig config = nullptr;
  GLXDrawable drawable = 0;
  GLXContext context = nullptr;
  /// false (with `error`) where there is no display, no 3.3 core context or no GLX
  bool create(std::string& error);
  /// the handles as engine::XrProgram takes them
  engine::GlxBinding binding() const { return m_window ? m_window->glxBinding() : engine::GlxBinding{}; }

 private:
  std::unique_ptr<engine::GlWindow> m_window;
};

}  // namespace fp::test
