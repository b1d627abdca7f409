#include "engine/xr_mirror.h"

// gl_api first: it brings GLEW, which must precede any other GL header
#include <imgui.h>
#include "render/gl_api.h"

#include <algorithm>

#include "engine/frame_capture.h"
#include "engine/gl_window.h"
#include "engine/imgui_layer.h"
#include "engine/key_map.h"

namespace fp::engine {

struct XrMirror::Impl {
  GlWindow& window;
  ImGuiLayer imgui;
  PanelState panel;
  FrameCapture capture;
  // the last left-eye image, kept so a frame the headset does not show still shows the mirror
  GLuint framebuffer = 0;
  GLuint texture = 0;
  int width = 0, height = 0;
  bool uiOpen = false;

  Impl(GlWindow& w, const CliOptions& options, std::optional<int> frames)
      : window(w), imgui(w), capture(options, frames, panel) {}
  ~Impl() {
    window.makeCurrent();
    if (framebuffer)
      glDeleteFramebuffers(1, &framebuffer);
    if (texture)
      glDeleteTextures(1, &texture);
  }

  void allocate(int w, int h) {
    if (w == width && h == height && texture)
      return;
    if (!framebuffer)
      glGenFramebuffers(1, &framebuffer);
    if (texture)
      glDeleteTextures(1, &texture);
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glBindTexture(GL_TEXTURE_2D, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    width = w;
    height = h;
  }
};

XrMirror::XrMirror(GlWindow& window, const CliOptions& options, std::optional<int> frames)
    : m(std::make_unique<Impl>(window, options, frames)) {
  m->panel.visible = !options.noPanel;
  m->panel.headset = true;
  m->panel.scenes = availableScenes();
}

XrMirror::~XrMirror() = default;

void XrMirror::input(AppSession& session, render::RenderSettings& settings) {
  m->window.pollEvents();
  if (m->uiOpen)
    ImGui::EndFrame();  // a frame that was not presented
  m->imgui.newFrame();
  m->uiOpen = true;
  const ImGuiIO& io = ImGui::GetIO();
  KeyTargets targets{session, m->panel, settings};
  for (const auto& [key, mods] : m->window.takeKeyPresses())
    applyKey(key, mods, targets, io.WantCaptureKeyboard, false);
  m->window.takeWheel();
  if (m->panel.fullscreen != m->window.fullscreen()) {
    m->window.setFullscreen(m->panel.fullscreen);
    m->panel.fullscreen = m->window.fullscreen();
  }
  drawPanel(session, m->panel, settings);
  drawHelp(m->panel);
}

void XrMirror::pollEvents() {
  m->window.pollEvents();
}

void XrMirror::copyEye(unsigned framebuffer, int width, int height) {
  m->allocate(width, height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m->framebuffer);
  glDisable(GL_SCISSOR_TEST);
  // a plain copy: with GL_FRAMEBUFFER_SRGB off an sRGB eye image is copied as stored
  glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
}

void XrMirror::present(AppSession& session, int frame) {
  const auto [fbw, fbh] = m->window.framebufferSize();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, std::max(fbw, 1), std::max(fbh, 1));
  glDisable(GL_SCISSOR_TEST);
  glClearColor(0.05f, 0.05f, 0.06f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  if (m->texture && fbw > 0 && fbh > 0) {
    // the eye's image as large as the window allows, its aspect kept
    const double scale = std::min(double(fbw) / m->width, double(fbh) / m->height);
    const int w = int(m->width * scale + 0.5), h = int(m->height * scale + 0.5);
    const int x = (fbw - w) / 2, y = (fbh - h) / 2;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, m->framebuffer);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glBlitFramebuffer(0, 0, m->width, m->height, x, y, x + w, y + h, GL_COLOR_BUFFER_BIT,
                      w == m->width && h == m->height ? GL_NEAREST : GL_LINEAR);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  m->capture.sceneDrawn(m->panel, fbw, fbh, session.simulation().scene().frameRate);
  if (m->uiOpen)
    m_uiVertices = m->imgui.render();
  else
    m->imgui.renderAgain();  // a frame drawn while the steps ran: the panel as it was
  m->uiOpen = false;
  m->capture.frameDrawn(m->panel, frame, fbw, fbh);
  m->window.swapBuffers();
}

void XrMirror::finish() {
  m->capture.finish();
}

bool XrMirror::closeRequested() const {
  return m->panel.quit || m->window.closeRequested();
}

bool XrMirror::takeRecentre() {
  const bool r = m->panel.recentre;
  m->panel.recentre = false;
  return r;
}

}  // namespace fp::engine
