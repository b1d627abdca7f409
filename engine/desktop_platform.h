#pragma once
/// The desktop platform of the app loop: the window and its context (engine/gl_window), the fluid renderer
/// drawing one view (renderView, as each VR eye does), the camera and the mouse hand (engine/view_control),
/// the keys (engine/key_map), the ImGui panel (engine/imgui_layer, engine/panel), and screenshots and frame
/// recording (engine/frame_capture). This file only wires them into the frame: poll events, new ImGui frame,
/// keys and mouse (the panel first: io.WantCaptureMouse), capture, draw, panel, present.

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/gl_window.h"

namespace fp::engine {

/// Wall time of the parts of the last frame on the main thread [ms].
struct FrameTiming {
  double input = 0;    ///< events, camera, hand
  double ui = 0;       ///< building the panel and drawing it (ImGui)
  double capture = 0;  ///< particle upload and spray
  double render = 0;   ///< the 3D view (renderView, finished)
  double present = 0;  ///< screenshot, frame recording and buffer swap
};

/// The window platform of the app loop.
class DesktopPlatform : public AppPlatform {
 public:
  /// Opens the window (options: size, fullscreen, view settings, screenshot, frame recording, panel). Throws
  /// WindowUnavailable without a display or context, render::RenderError for a missing or broken shader.
  /// `frames` is the --frames limit: the screenshot is taken at the last of them.
  DesktopPlatform(const CliOptions& options, std::optional<int> frames);
  ~DesktopPlatform() override;
  DesktopPlatform(const DesktopPlatform&) = delete;
  DesktopPlatform& operator=(const DesktopPlatform&) = delete;

  bool running() override;
  /// the wall clock: the time since the last frame
  FrameClock beginFrame() override;
  void input(AppSession& session, const FrameClock& clock) override;
  void capture(AppSession& session, int frame) override;
  void draw(AppSession& session, int frame) override;
  double stepBudget() const override;

  /// writes the screenshot of --screenshot if it was not written yet (a window closed before --frames)
  void finish();
  /// "GLFW, 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (...)"
  const std::string& contextDescription() const;
  /// timing of the last frame
  const FrameTiming& timing() const;
  /// vertices the panel and overlays drew in the last frame (0: no UI drawn)
  int uiVertexCount() const;
  /// asks the loop to stop
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

}  // namespace fp::engine
