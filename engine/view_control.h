#pragma once
/// The desktop window's camera and mouse hand: the orbit camera (right drag orbits, middle or Shift + right
/// drag pans, Ctrl + wheel or Z / X zooms) and the hand in a plane facing the camera (left drag sweeps, the
/// wheel or W / S moves it in depth, the side button makes a fist while held), framed on the scene whenever a
/// scene is loaded. Its mouse and held-key controls are declared here, beside the code that reads them.

#include <string>
#include <utility>
#include <vector>

#include "engine/app_session.h"
#include "render/camera.h"

namespace fp::engine {

class GlWindow;

/// The camera and the mouse hand of one window.
class ViewControl {
 public:
  /// Moves the camera and (unless a recording replays) the session's mouse hand from the window's mouse and
  /// held keys. `wheel`: the frame's wheel turn [notches]; `mouseFree`, `keysFree`: the panel does not hold
  /// the mouse / the keyboard; `dt`: the wall time of the frame [s].
  void update(GlWindow& window, AppSession& session, double wheel, bool mouseFree, bool keysFree, double dt);
  /// frames the session's scene when it first shows and whenever another scene is loaded; `aspect`: the
  /// framebuffer's width / height
  void frameScene(const AppSession& session, float aspect);

  /// the camera the view is drawn with
  const render::OrbitCamera& camera() const { return m_camera; }

  /// the mouse and held-key controls: (input, action) for the help overlay
  static const std::vector<std::pair<const char*, const char*>>& controls();

 private:
  render::OrbitCamera m_camera;
  std::string m_framedScene;
  double m_lastX = 0.0, m_lastY = 0.0;
  bool m_sideButton = false;
  input::Gesture m_gestureBeforeSideButton = input::Gesture::Flat;
};

}  // namespace fp::engine
