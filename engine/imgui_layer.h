#pragma once
/// Dear ImGui (1.86, GLFW and OpenGL3 back-ends) over a GlWindow: the canonical frame is poll events,
/// newFrame, read io.WantCaptureMouse before the app uses the mouse, build the windows, render, swap.

namespace fp::engine {

class GlWindow;

/// The ImGui context of one window; the window's context must be current when it is made and destroyed.
class ImGuiLayer {
 public:
  /// Throws WindowUnavailable when the OpenGL3 back-end cannot start on the window's context.
  explicit ImGuiLayer(GlWindow& window);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;

  /// starts the frame's ImGui windows (after the window's events were polled)
  void newFrame();
  /// draws the frame's ImGui windows into the bound framebuffer; returns the vertices drawn
  int render();
  /// draws the windows of the last render() again (nothing before the first)
  void renderAgain();
};

}  // namespace fp::engine
