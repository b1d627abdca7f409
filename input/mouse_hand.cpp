#include "input/mouse_hand.h"

#include <algorithm>
#include <cmath>

namespace fp::input {

sim::Vec3d cursorToWorld(const ViewFrame& view, double x, double y, int width, int height, double depth) {
  const double ndcX = 2.0 * x / double(std::max(width, 1)) - 1.0;
  const double ndcY = 1.0 - 2.0 * y / double(std::max(height, 1));
  const double t = std::tan(0.5 * view.fovY);
  // a ray whose forward component is 1, so `depth` is the distance along the view direction
  const sim::Vec3d ray = view.forward + view.right * (ndcX * t * view.aspect) + view.up * (ndcY * t);
  return view.eye + ray * depth;
}

Eigen::Vector2d worldToCursor(const ViewFrame& view, const sim::Vec3d& point, int width, int height) {
  const sim::Vec3d d = point - view.eye;
  const double depth = d.dot(view.forward);
  const double t = std::tan(0.5 * view.fovY);
  const double ndcX = d.dot(view.right) / (depth * t * view.aspect);
  const double ndcY = d.dot(view.up) / (depth * t);
  return Eigen::Vector2d(0.5 * (ndcX + 1.0) * width, 0.5 * (1.0 - ndcY) * height);
}

MouseHand::MouseHand(const HandPose& pose) {
  place(pose);
}

void MouseHand::place(const HandPose& pose) {
  m_position = pose.position;
  m_orientation = pose.orientation.normalized();
}

HandPose MouseHand::pose() const {
  HandPose p;
  p.position = m_position;
  p.orientation = m_orientation;
  p.grip = m_gesture.channels().grip;
  p.point = m_gesture.channels().point;
  return p;
}

void MouseHand::update(const ViewFrame& view, double cursorX, double cursorY, int width, int height,
                       bool follow, double depthSteps, double dt) {
  sim::Vec3d target = m_position;
  const double depth = std::max(0.05, (m_position - view.eye).dot(view.forward));
  if (follow)
    target = cursorToWorld(view, cursorX, cursorY, width, height, depth);
  target += view.forward * (depthSteps * depthStep);
  // a bounded speed: the water sees a hand, not a teleport, however fast the cursor jumps
  const sim::Vec3d move = target - m_position;
  const double limit = maxSpeed * std::max(dt, 0.0);
  const double length = move.norm();
  m_position += length > limit && length > 0.0 ? move * (limit / length) : move;
  m_position = m_position.cwiseMax(lo).cwiseMin(hi);
  // the palm (hand +x) faces the camera's horizontal view direction; fingers hang down
  sim::Vec3d horizontal(view.forward.x(), 0.0, view.forward.z());
  if (horizontal.norm() > 1e-6) {
    horizontal.normalize();
    const double yaw = std::atan2(-horizontal.z(), horizontal.x()) + yawOffset;
    m_orientation = sim::Quatd(Eigen::AngleAxisd(yaw, sim::Vec3d::UnitY()));
  }
  m_gesture.advance(dt);
}

}  // namespace fp::input
