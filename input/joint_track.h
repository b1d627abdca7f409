#pragma once
/// Recorded tracked hands: both hands' 26 joints (pose and radius) per frame, sampled with linear and
/// spherical interpolation, saved and loaded as a CSV text file, so a headset session can be replayed on the
/// desktop or headless.
///
/// CSV: the header "time,hand,joint,valid,px,py,pz,qw,qx,qy,qz,radius", then one line per joint: time [s]
/// from the start (the headset records a frame's simulated time, see engine/tracked_hands.h), hand "left" or
/// "right", the joint's name (input/joint_hand.h: palm, wrist, thumb_metacarpal, ..., little_tip), valid 1
/// (tracked) or 0, position [m] and orientation (joint -> world, w first) in the world frame of the scene,
/// radius [m]. A frame is the lines with one time: 26 lines of each hand it has, in joint order; a hand
/// without lines, or with valid 0, is not tracked in that frame.

#include <array>
#include <string>
#include <vector>

#include "input/joint_hand.h"

namespace fp::input {

/// Both hands at one instant.
struct JointFrame {
  double time = 0.0;                ///< [s] from the start of the recording
  std::array<HandJoints, 2> hands;  ///< indexed by HandSide
};

/// A sequence of joint frames with strictly increasing times.
class JointTrack {
 public:
  /// appends a frame; throws sim::InputError when its time is not after the last one or a value of a valid
  /// hand is not finite (or a radius not positive)
  void add(const JointFrame& frame);
  /// appends a frame, or replaces the last one when it has the same time (the last input of an instant
  /// wins); throws as add()
  void put(const JointFrame& frame);
  /// the frames
  const std::vector<JointFrame>& frames() const { return m_frames; }
  /// time of the last frame [s] (0 when empty)
  double duration() const;
  /// both hands at time t, clamped to the ends: a recorded frame's time gives that frame exactly, a hand
  /// valid in both surrounding frames is interpolated (positions and radii linear, orientations slerp),
  /// otherwise it is as in the earlier frame
  JointFrame sample(double t) const;

  /// reads the CSV; throws sim::InputError naming file and line
  static JointTrack load(const std::string& path);
  /// the CSV header line
  static const char* header();
  /// true when the file's first line is this format's header (to tell it from a pose track)
  static bool isJointFile(const std::string& path);
  /// writes the CSV (numbers in the shortest form that reads back exactly); throws sim::InputError
  void save(const std::string& path) const;

 private:
  std::vector<JointFrame> m_frames;
};

}  // namespace fp::input
