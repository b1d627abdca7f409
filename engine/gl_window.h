#pragma once
/// A GLFW window with an OpenGL 4.5 core context (3.3 core as fallback), current on the creating thread, GL
/// loaded through render/gl_api: the desktop window, the headset mode's mirror window, or (hidden) the
/// headset mode's context without a mirror. It gathers the window's key presses and wheel turns, and hands
/// out its native GLX handles so an OpenXR session renders in this one context.

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

struct GLFWwindow;

namespace fp::engine {

/// No window can be opened: no display, or no OpenGL 3.3 core context. The message is one line.
class WindowUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The GLX context a window renders with: Display*, GLXFBConfig, GLXDrawable and GLXContext as opaque values,
/// so this header needs no X11 or GLX header (what XR_KHR_opengl_enable's Xlib binding asks for).
struct GlxBinding {
  void* display = nullptr;
  void* fbConfig = nullptr;
  unsigned long drawable = 0;
  void* context = nullptr;
};

/// How to open the window.
struct GlWindowOptions {
  int width = 1280;                    ///< window size [screen px], > 0
  int height = 720;                    ///< [screen px], > 0
  bool visible = true;                 ///< false: an unmapped window, only for its context
  std::string title = "FluidPlaying";  ///< window title
  int swapInterval = 1;                ///< frames per buffer swap (0: do not wait for the display)
};

/// The window and its context. One at a time per process (it owns GLFW's initialisation).
class GlWindow {
 public:
  /// Opens the window and makes its context current. Throws WindowUnavailable (one line) without a display
  /// or a 3.3 core context, render::RenderError when the context lacks a required GL function.
  explicit GlWindow(const GlWindowOptions& options);
  ~GlWindow();
  GlWindow(const GlWindow&) = delete;
  GlWindow& operator=(const GlWindow&) = delete;

  /// the GLFW window (for input queries and the ImGui back-end)
  GLFWwindow* handle() const { return m_window; }
  /// "GLFW, 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (...)"
  const std::string& description() const { return m_description; }
  /// makes the context current on this thread
  void makeCurrent();
  /// the framebuffer size [px] (0 x 0 while minimised)
  std::pair<int, int> framebufferSize() const;
  /// the window size [screen px]
  std::pair<int, int> windowSize() const;
  /// true once the user asked to close the window (or requestClose was called)
  bool closeRequested() const;
  /// asks the window to close, as its close button does
  void requestClose();
  /// processes the window system's events (fills the key and wheel queues)
  void pollEvents();
  /// presents the back buffer
  void swapBuffers();
  /// the key presses since the last call: (GLFW key, GLFW modifier bits), oldest first
  std::vector<std::pair<int, int>> takeKeyPresses();
  /// the wheel's vertical turn since the last call [notches]
  double takeWheel();
  /// fullscreen on the primary monitor, or back to the windowed size and position
  void setFullscreen(bool on);
  bool fullscreen() const { return m_fullscreen; }
  /// the native GLX handles of this context; display is null where the context is not GLX (Wayland)
  GlxBinding glxBinding() const;

 private:
  GLFWwindow* m_window = nullptr;
  std::string m_description;
  std::vector<std::pair<int, int>> m_keys;
  double m_wheel = 0.0;
  bool m_fullscreen = false;
  int m_windowedPos[2] = {64, 64};
  int m_windowedSize[2] = {1280, 720};
};

}  // namespace fp::engine
