#include "engine/gl_window.h"

// gl_api first: it brings GLEW, which must precede any other GL header (GLFW's and GLX's included)
#include "render/gl_api.h"
// clang-format off
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <GL/glx.h>
#include <X11/Xlib.h>
// clang-format on

// GLFW's native access (glfw3native.h, which wants the XRandR development headers for one typedef)
extern "C" {
Display* glfwGetX11Display(void);
GLXContext glfwGetGLXContext(GLFWwindow* window);
GLXWindow glfwGetGLXWindow(GLFWwindow* window);
}

#include <dlfcn.h>

#include <cstdlib>

namespace fp::engine {

namespace {

std::string g_glfwError;  // GLFW reports errors through a plain callback

void glfwError(int code, const char* text) {
  g_glfwError = std::string(text) + " (" + std::to_string(code) + ")";
}

GlWindow* owner(GLFWwindow* w) {
  return static_cast<GlWindow*>(glfwGetWindowUserPointer(w));
}

}  // namespace

GlWindow::GlWindow(const GlWindowOptions& options) {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland))
    throw WindowUnavailable("no display (DISPLAY is unset)");
  glfwSetErrorCallback(glfwError);
  if (!glfwInit())
    throw WindowUnavailable("cannot open the display '" + std::string(display ? display : "") +
                            "': " + g_glfwError);
  m_windowedSize[0] = options.width;
  m_windowedSize[1] = options.height;
  // 4.5 core first, as the renderer asks everywhere; Xvfb's llvmpipe and older drivers may only give 3.3
  for (const auto& [major, minor] : {std::pair{4, 5}, std::pair{3, 3}}) {
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, major);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, minor);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
    m_window = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (m_window)
      break;
  }
  if (!m_window) {
    glfwTerminate();
    throw WindowUnavailable("no OpenGL 3.3 core window: " + g_glfwError);
  }
  glfwMakeContextCurrent(m_window);
  glfwSwapInterval(options.swapInterval);
  try {
    render::gl::loadFunctions(glfwGetProcAddress);
    m_description = "GLFW, " + render::gl::versionString();
  } catch (...) {
    glfwDestroyWindow(m_window);
    glfwTerminate();
    throw;
  }
  // installed before any ImGui back-end, which chains to them
  glfwSetWindowUserPointer(m_window, this);
  glfwSetScrollCallback(m_window, [](GLFWwindow* w, double, double dy) { owner(w)->m_wheel += dy; });
  glfwSetKeyCallback(m_window, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action == GLFW_PRESS)
      owner(w)->m_keys.emplace_back(key, mods);
  });
}

GlWindow::~GlWindow() {
  glfwDestroyWindow(m_window);
  glfwTerminate();
}

void GlWindow::makeCurrent() {
  glfwMakeContextCurrent(m_window);
}

std::pair<int, int> GlWindow::framebufferSize() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(m_window, &w, &h);
  return {w, h};
}

std::pair<int, int> GlWindow::windowSize() const {
  int w = 1, h = 1;
  glfwGetWindowSize(m_window, &w, &h);
  return {w, h};
}

bool GlWindow::closeRequested() const {
  return glfwWindowShouldClose(m_window);
}

void GlWindow::requestClose() {
  glfwSetWindowShouldClose(m_window, GLFW_TRUE);
}

void GlWindow::pollEvents() {
  glfwPollEvents();
}

void GlWindow::swapBuffers() {
  glfwSwapBuffers(m_window);
}

std::vector<std::pair<int, int>> GlWindow::takeKeyPresses() {
  std::vector<std::pair<int, int>> keys;
  keys.swap(m_keys);
  return keys;
}

double GlWindow::takeWheel() {
  const double wheel = m_wheel;
  m_wheel = 0.0;
  return wheel;
}

void GlWindow::setFullscreen(bool on) {
  if (on == m_fullscreen)
    return;
  GLFWmonitor* monitor = glfwGetPrimaryMonitor();
  const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
  if (on && mode) {
    glfwGetWindowPos(m_window, &m_windowedPos[0], &m_windowedPos[1]);
    glfwGetWindowSize(m_window, &m_windowedSize[0], &m_windowedSize[1]);
    glfwSetWindowMonitor(m_window, monitor, 0, 0, mode->width, mode->height, mode->refreshRate);
    m_fullscreen = true;
  } else if (!on) {
    glfwSetWindowMonitor(m_window, nullptr, m_windowedPos[0], m_windowedPos[1], m_windowedSize[0],
                         m_windowedSize[1], 0);
    m_fullscreen = false;
  }
}

GlxBinding GlWindow::glxBinding() const {
  GlxBinding b;
  Display* display = glfwGetX11Display();
  const GLXContext context = glfwGetGLXContext(m_window);
  const GLXWindow drawable = glfwGetGLXWindow(m_window);
  if (!display || !context || !drawable)
    return b;
  // GLFW keeps the context's framebuffer configuration to itself: ask GLX for it by its id. Through libGL's
  // own loader, so the window code links no GLX library.
  using QueryContext = int (*)(Display*, GLXContext, int, int*);
  using ChooseConfig = GLXFBConfig* (*)(Display*, int, const int*, int*);
  using Free = int (*)(void*);
  const auto query = reinterpret_cast<QueryContext>(render::gl::glxProcAddress("glXQueryContext"));
  const auto choose = reinterpret_cast<ChooseConfig>(render::gl::glxProcAddress("glXChooseFBConfig"));
  const auto release = reinterpret_cast<Free>(dlsym(RTLD_DEFAULT, "XFree"));  // libX11 is in: GLX uses it
  int id = 0, screen = 0;
  if (!query || !choose || query(display, context, GLX_FBCONFIG_ID, &id) != 0 ||
      query(display, context, GLX_SCREEN, &screen) != 0)
    return b;
  const int attributes[] = {GLX_FBCONFIG_ID, id, None};
  int count = 0;
  GLXFBConfig* configs = choose(display, screen, attributes, &count);
  if (!configs || count < 1)
    return b;
  b.display = display;
  b.fbConfig = configs[0];
  b.drawable = drawable;
  b.context = context;
  if (release)
    release(configs);
  return b;
}

}  // namespace fp::engine
