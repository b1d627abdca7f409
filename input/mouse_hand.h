#pragma once
/// The mouse-driven hand: the cursor moves the hand in a plane facing the camera, the wheel (or keys) in
/// depth, and gestures animate the fingers. Pure geometry on plain values, so it is tested without a window.

#include "input/hand_model.h"
#include "sim/types.h"

namespace fp::input {

/// A perspective view as the cursor mapping needs it.
struct ViewFrame {
  sim::Vec3d eye{0.0, 0.0, 3.0};       ///< camera position [m]
  sim::Vec3d forward{0.0, 0.0, -1.0};  ///< unit viewing direction
  sim::Vec3d right{1.0, 0.0, 0.0};     ///< unit, screen +x
  sim::Vec3d up{0.0, 1.0, 0.0};        ///< unit, screen +y
  double fovY = 0.8;                   ///< vertical field of view [rad], in (0, pi)
  double aspect = 1.0;                 ///< width / height, > 0
};

/// The world point under cursor (x, y) [px, y from the top] of a width x height viewport, on the plane facing
/// the camera at `depth` [m] in front of the eye (measured along `forward`).
sim::Vec3d cursorToWorld(const ViewFrame& view, double x, double y, int width, int height, double depth);
/// The cursor position [px, y from the top] of a world point in front of the camera; the inverse of
/// cursorToWorld at the point's depth.
Eigen::Vector2d worldToCursor(const ViewFrame& view, const sim::Vec3d& point, int width, int height);

/// The hand under the mouse: call update() once a frame with the cursor; read pose().
class MouseHand {
 public:
  /// Starts at `pose` (its position, and its yaw as the facing).
  explicit MouseHand(const HandPose& pose = HandPose{});

  /// Frame update. While `follow` (the sweep button is held) the palm goes to the cursor's point on the plane
  /// at the hand's depth; `depthSteps` (wheel notches or key presses, + away from the camera) move the hand
  /// along the view direction by `depthStep` each; the palm faces along the camera's horizontal view
  /// direction turned by `yawOffset`. The new position is limited to `maxSpeed` * dt away from the old one
  /// and clamped to the box [lo, hi]. `dt` [s] animates the fingers.
  void update(const ViewFrame& view, double cursorX, double cursorY, int width, int height, bool follow,
              double depthSteps, double dt);

  /// the pose after the last update
  HandPose pose() const;
  /// gestures
  GestureAnimator& gesture() { return m_gesture; }
  /// places the hand (reset): position and orientation of `pose`
  void place(const HandPose& pose);

  sim::Vec3d lo{-1e9, -1e9, -1e9};  ///< the palm stays in [lo, hi] [m]
  sim::Vec3d hi{1e9, 1e9, 1e9};     ///< the palm stays in [lo, hi] [m]
  double depthStep = 0.02;          ///< depth moved per wheel notch [m]
  double maxSpeed = 2.5;            ///< fastest hand motion [m/s]; a faster cursor is followed over frames
  double yawOffset = 0.0;           ///< extra turn of the palm about the vertical [rad]

 private:
  sim::Vec3d m_position{0.0, 0.0, 0.0};
  sim::Quatd m_orientation = sim::Quatd::Identity();
  GestureAnimator m_gesture;
};

}  // namespace fp::input
