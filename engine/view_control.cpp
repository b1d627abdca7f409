#include "engine/view_control.h"

// clang-format off
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
// clang-format on

#include <algorithm>
#include <cmath>

#include "engine/gl_window.h"
#include "engine/headless_render.h"

namespace fp::engine {

namespace {

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

const std::vector<std::pair<const char*, const char*>>& ViewControl::controls() {
  static const std::vector<std::pair<const char*, const char*>> list = {
      {"left button (hold)", "sweep: the hand follows the cursor in a plane facing the camera"},
      {"wheel / W, S (hold)", "hand away from / towards the camera"},
      {"side button (hold)", "fist while held"},
      {"right drag", "orbit the camera"},
      {"middle drag / Shift + right drag", "pan the camera"},
      {"Ctrl + wheel / Z, X (hold)", "zoom in / out"},
  };
  return list;
}

void ViewControl::frameScene(const AppSession& session, float aspect) {
  if (m_framedScene == session.scenePath())
    return;
  const Eigen::AlignedBox3f box = sceneViewBox(session.simulation());
  m_camera.frame(box.min(), box.max(), aspect);
  m_framedScene = session.scenePath();
}

void ViewControl::update(GlWindow& window, AppSession& session, double wheel, bool mouseFree, bool keysFree,
                         double dt) {
  GLFWwindow* w = window.handle();
  const auto [width, height] = window.windowSize();
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(w, &x, &y);
  const double dx = x - m_lastX, dy = y - m_lastY;
  m_lastX = x;
  m_lastY = y;
  auto held = [&](int button) { return mouseFree && glfwGetMouseButton(w, button) == GLFW_PRESS; };
  auto key = [&](int k) { return keysFree && glfwGetKey(w, k) == GLFW_PRESS; };
  const bool shift = key(GLFW_KEY_LEFT_SHIFT) || key(GLFW_KEY_RIGHT_SHIFT);
  const bool ctrl = key(GLFW_KEY_LEFT_CONTROL) || key(GLFW_KEY_RIGHT_CONTROL);
  render::OrbitCamera& cam = m_camera;
  const double aspect = double(width) / std::max(height, 1);
  const bool pan = held(GLFW_MOUSE_BUTTON_MIDDLE) || (shift && held(GLFW_MOUSE_BUTTON_RIGHT));
  if (pan) {
    const float scale = 2.0f * cam.distance * std::tan(0.5f * cam.fovY) / float(std::max(height, 1));
    const input::ViewFrame v = viewFrameOf(cam, aspect);
    cam.target += (-float(dx) * scale) * v.right.cast<float>() + (float(dy) * scale) * v.up.cast<float>();
  } else if (held(GLFW_MOUSE_BUTTON_RIGHT)) {
    cam.yaw -= float(dx) * 0.008f;
    cam.pitch = std::clamp(cam.pitch + float(dy) * 0.008f, -1.45f, 1.45f);
  }
  if (!mouseFree)
    wheel = 0.0;
  double zoomSteps = ctrl ? wheel : 0.0;
  if (key(GLFW_KEY_Z))
    zoomSteps += dt * 4.0;
  if (key(GLFW_KEY_X))
    zoomSteps -= dt * 4.0;
  cam.distance = std::clamp(cam.distance * std::pow(0.9f, float(zoomSteps)), 0.05f, 50.0f);
  double depthSteps = ctrl ? 0.0 : -wheel;  // wheel up brings the hand closer, like pulling it towards you
  input::MouseHand& hand = session.mouseHand();
  if (key(GLFW_KEY_W))
    depthSteps += dt * 0.4 / hand.depthStep;
  if (key(GLFW_KEY_S))
    depthSteps -= dt * 0.4 / hand.depthStep;
  const bool side = held(GLFW_MOUSE_BUTTON_4);
  if (side && !m_sideButton) {
    m_gestureBeforeSideButton = hand.gesture().target();
    hand.gesture().setTarget(input::Gesture::Fist);
  } else if (!side && m_sideButton) {
    hand.gesture().setTarget(m_gestureBeforeSideButton);
  }
  m_sideButton = side;
  const bool sweep = held(GLFW_MOUSE_BUTTON_LEFT);
  if (!session.replaying()) {
    hand.update(viewFrameOf(cam, aspect), x, y, width, height, sweep, depthSteps, dt);
    session.setHandTarget(hand.pose());
  }
}

}  // namespace fp::engine
