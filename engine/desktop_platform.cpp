#include "engine/desktop_platform.h"

// gl_api first: it brings GLEW, which must precede any other GL header (GLFW's included)
#include "render/gl_api.h"
// clang-format off
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
// clang-format on

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "engine/headless_render.h"
#include "engine/panel.h"
#include "render/camera.h"
#include "render/fluid_renderer.h"
#include "render/image.h"
#include "render/shader_program.h"
#include "sim/splash.h"

namespace fp::engine {

namespace {
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

std::string g_glfwError;  // GLFW reports errors through a plain callback

void glfwError(int code, const char* text) {
  g_glfwError = std::string(text) + " (" + std::to_string(code) + ")";
}

input::ViewFrame viewFrameOf(const render::OrbitCamera& camera, double aspect) {
  input::ViewFrame v;
  const Eigen::Vector3f eye = camera.eye();
  v.eye = eye.cast<double>();
  v.forward = (camera.target - eye).cast<double>().normalized();
  sim::Vec3d right = v.forward.cross(sim::Vec3d::UnitY());
  if (right.norm() < 1e-9)
    right = sim::Vec3d::UnitX();
  v.right = right.normalized();
  v.up = v.right.cross(v.forward).normalized();
  v.fovY = camera.fovY;
  v.aspect = aspect;
  return v;
}
}  // namespace

struct DesktopPlatform::Impl {
  GLFWwindow* window = nullptr;
  bool imgui = false;
  std::string description;
  std::unique_ptr<render::FluidRenderer> renderer;
  render::OrbitCamera camera;
  sim::SplashGenerator splash;
  PanelState panel;
  FrameTiming timing;
  std::optional<Clock::time_point> lastFrame;
  std::string framedScene;
  std::uint64_t framedBuild = ~0ull;
  int uiVertices = 0;
  // input gathered by the callbacks
  double wheel = 0.0;
  std::vector<std::pair<int, int>> keys;  // (key, mods) presses
  double lastX = 0.0, lastY = 0.0;
  bool fullscreen = false;
  int windowedPos[2] = {64, 64};
  int windowedSize[2] = {1280, 720};
  bool quit = false;
  input::Gesture gestureBeforeSideButton = input::Gesture::Flat;
  bool sideButton = false;
  // screenshots and recording
  std::string screenshotPath;
  std::optional<int> frames;
  std::optional<render::Image> lastImage;
  bool screenshotWritten = false;
  std::string recordDir;
  int recorded = 0;
  int screenshots = 0;

  void toggleFullscreen(bool on);
  void handleKey(AppSession& session, int key);
};

void DesktopPlatform::Impl::toggleFullscreen(bool on) {
  if (on == fullscreen)
    return;
  GLFWmonitor* monitor = glfwGetPrimaryMonitor();
  const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
  if (on && mode) {
    glfwGetWindowPos(window, &windowedPos[0], &windowedPos[1]);
    glfwGetWindowSize(window, &windowedSize[0], &windowedSize[1]);
    glfwSetWindowMonitor(window, monitor, 0, 0, mode->width, mode->height, mode->refreshRate);
    fullscreen = true;
  } else if (!on) {
    glfwSetWindowMonitor(window, nullptr, windowedPos[0], windowedPos[1], windowedSize[0], windowedSize[1],
                         0);
    fullscreen = false;
  }
  panel.fullscreen = fullscreen;
}

void DesktopPlatform::Impl::handleKey(AppSession& session, int key) {
  render::RenderSettings& s = renderer->settings();
  input::MouseHand& hand = session.mouseHand();
  switch (key) {
    case GLFW_KEY_SPACE:
      session.paused = !session.paused;
      break;
    case GLFW_KEY_N:
      session.paused = true;
      session.requests().singleStep = true;
      break;
    case GLFW_KEY_R:
      session.requests().reset = true;
      break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
      session.timeScale = std::min(4.0, session.timeScale * 1.25);
      break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
      session.timeScale = std::max(0.05, session.timeScale / 1.25);
      break;
    case GLFW_KEY_1:
      hand.gesture().setTarget(input::Gesture::Flat);
      break;
    case GLFW_KEY_2:
      hand.gesture().setTarget(input::Gesture::Fist);
      break;
    case GLFW_KEY_3:
      hand.gesture().setTarget(input::Gesture::Point);
      break;
    case GLFW_KEY_G:
      hand.gesture().setTarget(input::Gesture((int(hand.gesture().target()) + 1) % 3));
      break;
    case GLFW_KEY_Q:
    case GLFW_KEY_E:
      hand.yawOffset =
          std::clamp(hand.yawOffset + (key == GLFW_KEY_Q ? 1.0 : -1.0) * M_PI / 12.0, -M_PI / 2, M_PI / 2);
      break;
    case GLFW_KEY_V:
      s.view = s.view == render::RenderSettings::View::Fluid ? render::RenderSettings::View::Particles
                                                             : render::RenderSettings::View::Fluid;
      break;
    case GLFW_KEY_F5:
      if (session.recording()) {
        try {
          session.stopRecording().save(panel.recordingPath);
          panel.message = "hand motion saved to " + panel.recordingPath;
        } catch (const sim::InputError& e) {
          panel.message = e.what();
        }
      } else {
        session.startRecording();
        panel.message = "recording the hand (F5 stops)";
      }
      break;
    case GLFW_KEY_F6:
      if (session.replaying()) {
        session.stopReplay();
      } else {
        try {
          session.startReplay(input::PoseTrack::load(panel.recordingPath));
        } catch (const sim::InputError& e) {
          panel.message = e.what();
        }
      }
      break;
    case GLFW_KEY_F9:
      panel.recordFrames = !panel.recordFrames;
      break;
    case GLFW_KEY_F11:
      panel.fullscreen = !panel.fullscreen;
      break;
    case GLFW_KEY_F12:
      panel.screenshot = true;
      break;
    case GLFW_KEY_TAB:
      panel.visible = !panel.visible;
      break;
    case GLFW_KEY_F1:
    case GLFW_KEY_H:
      panel.help = !panel.help;
      break;
    case GLFW_KEY_ESCAPE:
      panel.help = false;
      break;
    default:
      break;
  }
}

DesktopPlatform::DesktopPlatform(const CliOptions& options, std::optional<int> frames)
    : m(std::make_unique<Impl>()) {
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((!display || !*display) && (!wayland || !*wayland))
    throw WindowUnavailable("no display (DISPLAY is unset)");
  glfwSetErrorCallback(glfwError);
  if (!glfwInit())
    throw WindowUnavailable("cannot open the display '" + std::string(display ? display : "") +
                            "': " + g_glfwError);
  m->windowedSize[0] = options.sizeGiven ? options.width : 1280;
  m->windowedSize[1] = options.sizeGiven ? options.height : 720;
  // 4.5 core first, as the renderer asks everywhere; Xvfb's llvmpipe and older drivers may only give 3.3
  for (const auto& [major, minor] : {std::pair{4, 5}, std::pair{3, 3}}) {
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, major);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, minor);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    m->window = glfwCreateWindow(m->windowedSize[0], m->windowedSize[1], "FluidPlaying", nullptr, nullptr);
    if (m->window)
      break;
  }
  if (!m->window) {
    glfwTerminate();
    throw WindowUnavailable("no OpenGL 3.3 core window: " + g_glfwError);
  }
  glfwMakeContextCurrent(m->window);
  glfwSwapInterval(1);
  try {
    render::gl::loadFunctions(glfwGetProcAddress);
    m->description = "GLFW, " + render::gl::versionString();
    m->renderer = std::make_unique<render::FluidRenderer>(
        options.shaderDir.empty() ? render::defaultShaderDir() : options.shaderDir);
  } catch (...) {
    glfwDestroyWindow(m->window);
    glfwTerminate();
    throw;
  }
  applyRenderOptions(options, m->renderer->settings());
  m->panel.visible = !options.noPanel;
  m->panel.scenes = availableScenes();
  m->screenshotPath = options.screenshot;
  m->frames = frames;
  m->recordDir = options.recordDir;
  m->panel.recordFrames = !m->recordDir.empty();
  if (m->recordDir.empty())
    m->recordDir = "frames";

  // our callbacks first: ImGui's GLFW back-end chains to them
  glfwSetWindowUserPointer(m->window, m.get());
  glfwSetScrollCallback(m->window, [](GLFWwindow* w, double, double dy) {
    static_cast<Impl*>(glfwGetWindowUserPointer(w))->wheel += dy;
  });
  glfwSetKeyCallback(m->window, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action == GLFW_PRESS)
      static_cast<Impl*>(glfwGetWindowUserPointer(w))->keys.emplace_back(key, mods);
  });
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini dropped into the working directory
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Alpha = 0.95f;
  ImGui_ImplGlfw_InitForOpenGL(m->window, true);
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) {
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(m->window);
    glfwTerminate();
    throw WindowUnavailable("the ImGui OpenGL3 back-end cannot start on this context");
  }
  m->imgui = true;
  if (options.fullscreen)
    m->toggleFullscreen(true);
}

DesktopPlatform::~DesktopPlatform() {
  if (!m->window)
    return;
  glfwMakeContextCurrent(m->window);
  if (m->imgui) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  m->renderer.reset();  // GL objects go while their context is current
  glfwDestroyWindow(m->window);
  glfwTerminate();
}

bool DesktopPlatform::running() {
  return !m->quit && !glfwWindowShouldClose(m->window);
}

void DesktopPlatform::close() {
  m->quit = true;
}

const std::string& DesktopPlatform::contextDescription() const {
  return m->description;
}

const FrameTiming& DesktopPlatform::timing() const {
  return m->timing;
}

int DesktopPlatform::uiVertexCount() const {
  return m->uiVertices;
}

double DesktopPlatform::stepBudget() const {
  // the steps run while the frame is drawn: they may take as long as drawing did, and at least a 60 Hz frame
  const double drawing = (m->timing.render + m->timing.ui + m->timing.present) * 1e-3;
  return std::clamp(drawing, 1.0 / 60.0, 0.25);
}

FrameClock DesktopPlatform::beginFrame() {
  const auto now = Clock::now();
  FrameClock clock;
  clock.dt = m->lastFrame ? std::chrono::duration<double>(now - *m->lastFrame).count() : 0.0;
  m->lastFrame = now;
  return clock;
}

void DesktopPlatform::input(AppSession& session, const FrameClock& clock) {
  const double wallDt = clock.dt;
  const auto start = Clock::now();
  glfwPollEvents();
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  const ImGuiIO& io = ImGui::GetIO();

  std::vector<std::pair<int, int>> keys;
  keys.swap(m->keys);
  for (const auto& [key, mods] : keys) {
    if (key == GLFW_KEY_Q && (mods & GLFW_MOD_CONTROL))
      m->quit = true;
    else if (!io.WantCaptureKeyboard)
      m->handleKey(session, key);
  }
  if (m->panel.fullscreen != m->fullscreen)
    m->toggleFullscreen(m->panel.fullscreen);

  int width = 1, height = 1;
  glfwGetWindowSize(m->window, &width, &height);
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(m->window, &x, &y);
  const double dx = x - m->lastX, dy = y - m->lastY;
  m->lastX = x;
  m->lastY = y;
  // the panel owns the mouse while it is over it (or a drag started on it)
  const bool mouse = !io.WantCaptureMouse;
  auto held = [&](int button) { return mouse && glfwGetMouseButton(m->window, button) == GLFW_PRESS; };
  auto key = [&](int k) { return !io.WantCaptureKeyboard && glfwGetKey(m->window, k) == GLFW_PRESS; };
  const bool shift = key(GLFW_KEY_LEFT_SHIFT) || key(GLFW_KEY_RIGHT_SHIFT);
  const bool ctrl = key(GLFW_KEY_LEFT_CONTROL) || key(GLFW_KEY_RIGHT_CONTROL);
  render::OrbitCamera& cam = m->camera;
  const bool pan = held(GLFW_MOUSE_BUTTON_MIDDLE) || (shift && held(GLFW_MOUSE_BUTTON_RIGHT));
  if (pan) {
    const float scale = 2.0f * cam.distance * std::tan(0.5f * cam.fovY) / float(std::max(height, 1));
    const input::ViewFrame v = viewFrameOf(cam, double(width) / std::max(height, 1));
    cam.target += (-float(dx) * scale) * v.right.cast<float>() + (float(dy) * scale) * v.up.cast<float>();
  } else if (held(GLFW_MOUSE_BUTTON_RIGHT)) {
    cam.yaw -= float(dx) * 0.008f;
    cam.pitch = std::clamp(cam.pitch + float(dy) * 0.008f, -1.45f, 1.45f);
  }
  double wheel = mouse ? m->wheel : 0.0;
  m->wheel = 0.0;
  double zoomSteps = ctrl ? wheel : 0.0;
  if (key(GLFW_KEY_Z))
    zoomSteps += wallDt * 4.0;
  if (key(GLFW_KEY_X))
    zoomSteps -= wallDt * 4.0;
  cam.distance = std::clamp(cam.distance * std::pow(0.9f, float(zoomSteps)), 0.05f, 50.0f);
  double depthSteps = ctrl ? 0.0 : -wheel;  // wheel up brings the hand closer, like pulling it towards you
  input::MouseHand& hand = session.mouseHand();
  if (key(GLFW_KEY_W))
    depthSteps += wallDt * 0.4 / hand.depthStep;
  if (key(GLFW_KEY_S))
    depthSteps -= wallDt * 0.4 / hand.depthStep;
  const bool side = held(GLFW_MOUSE_BUTTON_4);
  if (side && !m->sideButton) {
    m->gestureBeforeSideButton = hand.gesture().target();
    hand.gesture().setTarget(input::Gesture::Fist);
  } else if (!side && m->sideButton) {
    hand.gesture().setTarget(m->gestureBeforeSideButton);
  }
  m->sideButton = side;
  const bool sweep = held(GLFW_MOUSE_BUTTON_LEFT);
  if (!session.replaying()) {
    hand.update(viewFrameOf(cam, double(width) / std::max(height, 1)), x, y, width, height, sweep, depthSteps,
                wallDt);
    session.setHandTarget(hand.pose());
  }
  m->timing.input = msSince(start);

  const auto ui = Clock::now();
  drawPanel(session, m->panel, m->renderer->settings());
  drawHelp(m->panel);
  m->timing.ui = msSince(ui);
}

void DesktopPlatform::capture(AppSession& session, int frame) {
  const auto start = Clock::now();
  const sim::Simulation& simulation = session.simulation();
  int fbw = 1, fbh = 1;
  glfwGetFramebufferSize(m->window, &fbw, &fbh);
  // frame the scene when it first shows and whenever another scene is loaded
  if (m->framedScene != session.scenePath()) {
    const Eigen::AlignedBox3f box = sceneViewBox(simulation);
    m->camera.frame(box.min(), box.max(), float(fbw) / float(std::max(fbh, 1)));
    m->framedScene = session.scenePath();
  }
  render::SpraySpan spray;
  if (m->renderer->settings().showSpray) {
    const sim::SplashParticles& s = m->splash.generate(simulation, std::uint64_t(frame));
    spray = render::SpraySpan{s.x.data(), s.radius.data(), s.size()};
  }
  m->renderer->update(render::frameDataOf(simulation, spray));
  m->timing.capture = msSince(start);
}

void DesktopPlatform::draw(AppSession&, int frame) {
  auto start = Clock::now();
  int fbw = 1, fbh = 1;
  glfwGetFramebufferSize(m->window, &fbw, &fbh);
  if (fbw > 0 && fbh > 0) {
    render::RenderTarget target;
    target.width = fbw;
    target.height = fbh;
    const float aspect = float(fbw) / float(fbh);
    // one view today; a headset renders each eye through the same call
    m->renderer->renderView(m->camera.view(), m->camera.projection(aspect), target);
  }
  glFinish();  // so the render time is the GPU's (llvmpipe's) work, not just the command submission
  m->timing.render = msSince(start);

  start = Clock::now();
  std::error_code ec;
  if (m->panel.recordFrames && fbw > 0) {
    std::filesystem::create_directories(m->recordDir, ec);
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", m->recorded++);
    render::writePng((std::filesystem::path(m->recordDir) / name).string(),
                     render::readFramebuffer(0, 0, 0, fbw, fbh));
  }
  const double beforeUi = msSince(start);
  const auto ui = Clock::now();
  ImGui::Render();
  ImDrawData* data = ImGui::GetDrawData();
  m->uiVertices = data ? data->TotalVtxCount : 0;
  ImGui_ImplOpenGL3_RenderDrawData(data);
  glFinish();
  m->timing.ui += msSince(ui);

  start = Clock::now();
  if (m->panel.screenshot && fbw > 0) {
    m->panel.screenshot = false;
    char name[40];
    std::snprintf(name, sizeof(name), "screenshot_%03d.png", m->screenshots++);
    render::writePng(name, render::readFramebuffer(0, 0, 0, fbw, fbh));
    m->panel.message = std::string("screenshot written to ") + name;
  }
  if (!m->screenshotPath.empty() && fbw > 0) {
    const bool last = m->frames && frame == *m->frames - 1;
    if (last || !m->frames) {
      // without --frames any frame may be the last: keep it, write it when the window closes
      m->lastImage = render::readFramebuffer(0, 0, 0, fbw, fbh);
      if (last)
        finish();
    }
  }
  glfwSwapBuffers(m->window);
  m->timing.present = beforeUi + msSince(start);
}

void DesktopPlatform::finish() {
  if (m->screenshotWritten || m->screenshotPath.empty() || !m->lastImage)
    return;
  const std::filesystem::path parent = std::filesystem::path(m->screenshotPath).parent_path();
  std::error_code ec;
  if (!parent.empty())
    std::filesystem::create_directories(parent, ec);
  render::writePng(m->screenshotPath, *m->lastImage);
  m->screenshotWritten = true;
}

}  // namespace fp::engine
