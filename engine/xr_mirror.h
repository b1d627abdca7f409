#pragma once
/// The headset mode's desktop mirror: the window the OpenXR session renders in (one GL context), showing the
/// left eye's image of every frame with the desktop app's ImGui panel over it, so a second person can tune
/// the level intervals and splash parameters while someone plays. Closing it (or Ctrl+Q) ends the session. No
/// OpenXR type here: the XR platform hands it the left eye's framebuffer.

#include <memory>
#include <optional>

#include "engine/app_session.h"
#include "engine/cli.h"
#include "engine/panel.h"
#include "render/fluid_renderer.h"

namespace fp::engine {

class GlWindow;

/// The mirror of one visible window; its context must be current for every call.
class XrMirror {
 public:
  /// Starts ImGui on `window`; `options`: --no-panel, --screenshot (the mirror's last frame, with the panel),
  /// --record-dir; `frames`: the --frames limit. Throws WindowUnavailable when ImGui cannot start.
  XrMirror(GlWindow& window, const CliOptions& options, std::optional<int> frames);
  ~XrMirror();
  XrMirror(const XrMirror&) = delete;
  XrMirror& operator=(const XrMirror&) = delete;

  /// the window's events, its keys and the panel of this frame (edits go to `session` and `settings`)
  void input(AppSession& session, render::RenderSettings& settings);
  /// the window's events only (a frame drawn while the steps run: its keys and panel wait for the next input)
  void pollEvents();
  /// copies the left eye's `width` x `height` [px] image from `framebuffer` (read before it is released)
  void copyEye(unsigned framebuffer, int width, int height);
  /// draws the last eye image, letterboxed to the window, the panel over it (the last one drawn when input
  /// was not called this frame), writes what frame capture asks (the --screenshot at frame `frame`), and
  /// presents
  void present(AppSession& session, int frame);
  /// writes the --screenshot if it was not written yet
  void finish();

  /// the user closed the window or pressed Ctrl+Q
  bool closeRequested() const;
  /// the Recentre button was pressed since the last call
  bool takeRecentre();
  /// vertices the panel drew in the last frame
  int uiVertexCount() const { return m_uiVertices; }

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
  int m_uiVertices = 0;
};

}  // namespace fp::engine
