#pragma once
/// An orbit camera that produces the view and projection matrices of one view; the desktop window, each VR
/// eye and the headless mode all hand such a pair to the renderer.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace fp::render {

/// Column-major 4x4 matrices, as OpenGL expects.
using Mat4 = Eigen::Matrix4f;

/// Right-handed look-at view matrix (camera looks down -z).
Mat4 lookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up);
/// OpenGL perspective projection; fovY in radians, clip depths in [-1, 1].
Mat4 perspective(float fovY, float aspect, float zNear, float zFar);

/// An asymmetric field of view as a headset reports it per eye (XrFovf): the angles of the frustum's four
/// sides from the view axis [rad], left and down negative for a view axis inside the frustum, each in
/// (-pi/2, pi/2), left < right, down < up.
struct FieldOfView {
  float angleLeft = -0.8f;  ///< [rad]
  float angleRight = 0.8f;  ///< [rad]
  float angleUp = 0.8f;     ///< [rad]
  float angleDown = -0.8f;  ///< [rad]
};

/// Off-axis OpenGL projection of an asymmetric field of view (the frustum through the four angles at the near
/// plane), clip depths in [-1, 1]; 0 < zNear < zFar [m]. A symmetric `fov` gives perspective()'s matrix.
Mat4 offAxisPerspective(const FieldOfView& fov, float zNear, float zFar);

/// View matrix (world -> eye) of an eye at `position` [m] with orientation `orientation` (eye -> world; the
/// eye looks down its -z, +y up), as a headset reports a view pose.
Mat4 viewFromPose(const Eigen::Vector3f& position, const Eigen::Quaternionf& orientation);

/// A camera orbiting a target: yaw and pitch in radians, distance in metres.
struct OrbitCamera {
  Eigen::Vector3f target{0.0f, 0.0f, 0.0f};  ///< point looked at [m]
  float yaw = 0.6f;                          ///< rotation about +y [rad]
  float pitch = 0.35f;                       ///< elevation above the xz plane [rad], |pitch| < pi/2
  float distance = 3.0f;                     ///< from target [m], > 0
  float fovY = 0.8f;                         ///< vertical field of view [rad]

  /// eye position [m]
  Eigen::Vector3f eye() const;
  /// view matrix
  Mat4 view() const;
  /// projection matrix for an aspect ratio width/height, near and far planes fitted to the distance
  Mat4 projection(float aspect) const;
  /// places the camera on the box centre, as close as keeps every corner of [lo, hi] in view (at 92% of the
  /// half-extent) at the current yaw and pitch
  void frame(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float aspect);
};

}  // namespace fp::render
