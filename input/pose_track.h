#pragma once
/// Recorded motion of a collider (a hand, a paddle): time-stamped poses with two gesture channels, sampled
/// with linear and spherical interpolation, saved and loaded as a CSV text file so interactions are
/// reproducible.

#include <string>
#include <vector>

#include "sim/types.h"

namespace fp::input {

/// One keyframe, or the result of sampling a track.
struct PoseSample {
  double time = 0.0;                                ///< [s] from the start of the track
  sim::Vec3d position{0.0, 0.0, 0.0};               ///< [m], world
  sim::Quatd orientation = sim::Quatd::Identity();  ///< local -> world
  double grip = 0.0;                                ///< gesture: 0 open flat .. 1 fist [-]
  sim::Vec3d linearVelocity{0.0, 0.0, 0.0};         ///< [m/s], filled by sample()
  sim::Vec3d angularVelocity{0.0, 0.0, 0.0};        ///< [rad/s], world, filled by sample()
  double point = 0.0;                               ///< gesture: 0 .. 1 index finger straightened [-]
};

/// A sequence of keyframes with strictly increasing times.
class PoseTrack {
 public:
  /// appends a keyframe; throws sim::InputError when its time is not after the last one or a value is not
  /// finite
  void add(const PoseSample& key);
  /// the keyframes
  const std::vector<PoseSample>& keys() const { return m_keys; }
  /// time of the last keyframe [s] (0 when empty)
  double duration() const;
  /// pose at time t: position and grip linear, orientation slerp, clamped to the ends; velocities are those
  /// of the segment containing t (zero outside the track or with fewer than two keys)
  PoseSample sample(double t) const;

  /// CSV: header "time,px,py,pz,qw,qx,qy,qz,grip" or "time,px,py,pz,qw,qx,qy,qz,grip,point", one keyframe
  /// a line (point is 0 without its column). Throws sim::InputError naming file and line.
  static PoseTrack load(const std::string& path);
  /// writes the CSV, with the point column only when a key has point != 0; throws sim::InputError when the
  /// file cannot be written
  void save(const std::string& path) const;

 private:
  std::vector<PoseSample> m_keys;
};

}  // namespace fp::input
