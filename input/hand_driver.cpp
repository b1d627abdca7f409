#include "input/hand_driver.h"

#include <cmath>

namespace fp::input {

HandPose handPoseOf(const PoseSample& sample) {
  HandPose p;
  p.position = sample.position;
  p.orientation = sample.orientation;
  p.grip = sample.grip;
  p.point = sample.point;
  return p;
}

PoseSample poseSampleOf(double t, const HandPose& pose) {
  PoseSample s;
  s.time = t;
  s.position = pose.position;
  s.orientation = pose.orientation;
  s.grip = pose.grip;
  s.point = pose.point;
  return s;
}

sim::Vec3d rotationBetween(const sim::Quatd& q0, const sim::Quatd& q1) {
  sim::Quatd dq = q1 * q0.conjugate();
  if (dq.w() < 0.0)
    dq.coeffs() = -dq.coeffs();
  const double s = dq.vec().norm();
  if (s == 0.0)
    return sim::Vec3d::Zero();
  return dq.vec() * (2.0 * std::atan2(s, dq.w()) / s);
}

HandDriver HandDriver::attach(sim::SceneDesc& scene, const HandModel& model, const HandPose& initial) {
  const std::size_t first = scene.colliders.size();
  for (sim::ColliderDesc& c : model.colliders(initial))
    scene.colliders.push_back(std::move(c));
  return HandDriver(model, first);
}

void HandDriver::apply(sim::Simulation& simulation, const PoseTrack& motion, double trackStart,
                       double stepEstimate) const {
  const double t = simulation.time() - trackStart;
  const double h = stepEstimate > 0.0 ? stepEstimate : 1e-3;
  // Both ends of the step come from the track, so every part (the palm and each curling finger segment) moves
  // exactly onto the next step's pose: velocities by difference, not from the keys.
  const auto now = m_model.partPoses(handPoseOf(motion.sample(t)));
  const auto next = m_model.partPoses(handPoseOf(motion.sample(t + h)));
  for (int k = 0; k < HandModel::kParts; ++k) {
    const sim::Vec3d v = (next[k].position - now[k].position) / h;
    const sim::Vec3d w = rotationBetween(now[k].orientation, next[k].orientation) / h;
    simulation.setColliderPose(m_first + std::size_t(k), now[k].position, now[k].orientation, v, w);
  }
}

void HandDriver::place(sim::Simulation& simulation, const HandPose& pose) const {
  const auto parts = m_model.partPoses(pose);
  for (int k = 0; k < HandModel::kParts; ++k) {
    simulation.setColliderPose(m_first + std::size_t(k), parts[k].position, parts[k].orientation,
                               sim::Vec3d::Zero(), sim::Vec3d::Zero());
  }
}

}  // namespace fp::input
