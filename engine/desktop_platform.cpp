#include "engine/desktop_platform.h"

// gl_api first: it brings GLEW, which must precede any other GL header (ImGui's back-ends included)
#include <imgui.h>
#include "render/gl_api.h"

#include <algorithm>
#include <chrono>

#include "engine/frame_capture.h"
#include "engine/frame_splash.h"
#include "engine/imgui_layer.h"
#include "engine/key_map.h"
#include "engine/panel.h"
#include "engine/view_control.h"
#include "render/fluid_renderer.h"
#include "render/shader_program.h"

namespace fp::engine {

namespace {
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

GlWindowOptions windowOptionsOf(const CliOptions& options) {
  GlWindowOptions w;
  w.width = options.sizeGiven ? options.width : 1280;
  w.height = options.sizeGiven ? options.height : 720;
  return w;
}
}  // namespace

struct DesktopPlatform::Impl {
  // declared in construction order: the window (and its context) outlives what draws in it
  GlWindow window;
  std::unique_ptr<render::FluidRenderer> renderer;
  std::unique_ptr<ImGuiLayer> imgui;
  ViewControl view;
  FrameSplash splash;  // a paused simulation keeps its splash, not one a frame
  PanelState panel;
  FrameCapture frames;
  FrameTiming timing;
  std::optional<Clock::time_point> lastFrame;
  int uiVertices = 0;

  Impl(const CliOptions& options, std::optional<int> frameLimit)
      : window(windowOptionsOf(options)),
        renderer(std::make_unique<render::FluidRenderer>(
            options.shaderDir.empty() ? render::defaultShaderDir() : options.shaderDir)),
        frames(options, frameLimit, panel) {}
  ~Impl() {
    window.makeCurrent();
    imgui.reset();
    renderer.reset();  // GL objects go while their context is current
  }
};

DesktopPlatform::DesktopPlatform(const CliOptions& options, std::optional<int> frames)
    : m(std::make_unique<Impl>(options, frames)) {
  applyRenderOptions(options, m->renderer->settings());
  m->panel.visible = !options.noPanel;
  m->panel.scenes = availableScenes();
  m->imgui = std::make_unique<ImGuiLayer>(m->window);
  if (options.fullscreen) {
    m->window.setFullscreen(true);
    m->panel.fullscreen = m->window.fullscreen();
  }
}

DesktopPlatform::~DesktopPlatform() = default;

bool DesktopPlatform::running() {
  return !m->panel.quit && !m->window.closeRequested();
}

void DesktopPlatform::close() {
  m->panel.quit = true;
}

const std::string& DesktopPlatform::contextDescription() const {
  return m->window.description();
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
  const auto start = Clock::now();
  m->window.pollEvents();
  m->imgui->newFrame();
  const ImGuiIO& io = ImGui::GetIO();
  KeyTargets targets{session, m->panel, m->renderer->settings()};
  for (const auto& [key, mods] : m->window.takeKeyPresses())
    applyKey(key, mods, targets, io.WantCaptureKeyboard);
  if (m->panel.fullscreen != m->window.fullscreen()) {
    m->window.setFullscreen(m->panel.fullscreen);
    m->panel.fullscreen = m->window.fullscreen();
  }
  // the panel owns the mouse while it is over it (or a drag started on it)
  m->view.update(m->window, session, m->window.takeWheel(), !io.WantCaptureMouse, !io.WantCaptureKeyboard,
                 clock.dt);
  m->timing.input = msSince(start);

  const auto ui = Clock::now();
  drawPanel(session, m->panel, m->renderer->settings());
  drawHelp(m->panel);
  m->timing.ui = msSince(ui);
}

void DesktopPlatform::capture(AppSession& session, int frame) {
  const auto start = Clock::now();
  const sim::Simulation& simulation = session.simulation();
  const auto [fbw, fbh] = m->window.framebufferSize();
  m->view.frameScene(session, float(fbw) / float(std::max(fbh, 1)));
  render::SpraySpan spray;
  if (m->renderer->settings().showSpray) {
    const sim::SplashParticles& s = m->splash.of(simulation, std::uint64_t(frame));
    spray = render::SpraySpan{s.x.data(), s.radius.data(), s.size()};
  }
  m->renderer->update(render::frameDataOf(simulation, spray));
  m->timing.capture = msSince(start);
}

void DesktopPlatform::draw(AppSession& session, int frame) {
  auto start = Clock::now();
  const auto [fbw, fbh] = m->window.framebufferSize();
  if (fbw > 0 && fbh > 0) {
    render::RenderTarget target;
    target.width = fbw;
    target.height = fbh;
    const float aspect = float(fbw) / float(fbh);
    m->renderer->renderView(m->view.camera().view(), m->view.camera().projection(aspect), target);
  }
  glFinish();  // so the render time is the GPU's (llvmpipe's) work, not just the command submission
  m->timing.render = msSince(start);

  start = Clock::now();
  m->frames.sceneDrawn(m->panel, fbw, fbh, session.simulation().scene().frameRate);
  const double beforeUi = msSince(start);
  const auto ui = Clock::now();
  m->uiVertices = m->imgui->render();
  glFinish();
  m->timing.ui += msSince(ui);

  start = Clock::now();
  m->frames.frameDrawn(m->panel, frame, fbw, fbh);
  m->window.swapBuffers();
  m->timing.present = beforeUi + msSince(start);
}

void DesktopPlatform::finish() {
  m->frames.finish();
}

}  // namespace fp::engine
