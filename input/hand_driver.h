#pragma once
/// Drives the hand's colliders in a simulation: before every solver step it poses each part at the step's
/// start and gives it the velocity that carries it to the pose at the step's end, so the boundary particles
/// move with the hand and a fast hand never jumps through the water between steps (the motion is interpolated
/// across the solver steps of a frame).

#include <cstddef>

#include "input/hand_model.h"
#include "input/pose_track.h"
#include "sim/simulation.h"

namespace fp::input {

/// the hand pose of a pose-track sample (position, orientation, grip, point)
HandPose handPoseOf(const PoseSample& sample);
/// a pose-track keyframe at time t of a hand pose
PoseSample poseSampleOf(double t, const HandPose& pose);

/// The hand in one simulation: its model and the index of its first collider (the parts follow in order).
class HandDriver {
 public:
  /// Appends the hand's colliders, placed at `initial`, to `scene` and returns the driver of them.
  static HandDriver attach(sim::SceneDesc& scene, const HandModel& model, const HandPose& initial);
  /// A driver for a hand whose colliders already start at `firstCollider` of a scene.
  HandDriver(const HandModel& model, std::size_t firstCollider) : m_model(model), m_first(firstCollider) {}

  /// the geometry
  const HandModel& model() const { return m_model; }
  /// index of the palm collider; the finger segments follow
  std::size_t firstCollider() const { return m_first; }

  /// Sets every hand collider for the step that starts at the simulation's time: the pose of `motion` at that
  /// time, and linear and angular velocities that reach the pose at time + `stepEstimate` [s] (> 0). The
  /// track's time 0 is simulated time `trackStart` [s].
  void apply(sim::Simulation& simulation, const PoseTrack& motion, double trackStart,
             double stepEstimate) const;
  /// Sets the hand at rest at `pose` (pause, reset): no velocity.
  void place(sim::Simulation& simulation, const HandPose& pose) const;

 private:
  HandModel m_model;
  std::size_t m_first = 0;
};

/// The world rotation vector (axis * angle) of the shortest rotation from q0 to q1 [rad].
sim::Vec3d rotationBetween(const sim::Quatd& q0, const sim::Quatd& q1);

}  // namespace fp::input
