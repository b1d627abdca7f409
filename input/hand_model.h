#pragma once
/// The articulated virtual hand: a palm and five fingers of three segments each, as capsules at adult-hand
/// size, posed by a root pose and two gesture channels (grip: flat .. fist, point: index straight). The hand
/// acts on the water as driven kinematic colliders (sim::ColliderDesc::driven), one per part.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/scene.h"
#include "sim/types.h"

namespace fp::input {

/// Hand gestures the mouse and the recordings select.
enum class Gesture { Flat, Fist, Point };

/// "flat", "fist" or "point"
const char* gestureName(Gesture g);
/// the gesture named `name`, or nothing
std::optional<Gesture> parseGesture(std::string_view name);

/// The two gesture channels: grip 0 open flat .. 1 fist, point 0 .. 1 index finger straightened.
struct GestureChannels {
  double grip = 0.0;   ///< [0, 1]
  double point = 0.0;  ///< [0, 1]
};

/// the channel values a gesture settles at: flat (0, 0), fist (1, 0), point (1, 1)
GestureChannels gestureChannels(Gesture g);

/// Curl of each finger, thumb first (thumb, index, middle, ring, little), 0 straight .. 1 fully curled, from
/// the channels: the index finger curls with grip * (1 - point), the others with max(grip, point).
std::array<double, 5> fingerCurl(double grip, double point);

/// Animates the gesture channels towards the selected gesture at a bounded rate, so fingers close and open
/// over a fraction of a second instead of jumping (a jump would hit the water with an unbounded velocity).
class GestureAnimator {
 public:
  /// the gesture the channels move towards
  void setTarget(Gesture g) { m_target = g; }
  /// the target gesture
  Gesture target() const { return m_target; }
  /// moves the channels by at most rate * dt towards the target; dt [s] >= 0
  void advance(double dt);
  /// current channels
  const GestureChannels& channels() const { return m_current; }
  /// full-range change per second [1/s], > 0 (default 4: a fist closes in 0.25 s)
  double rate = 4.0;

 private:
  Gesture m_target = Gesture::Flat;
  GestureChannels m_current;
};

/// Pose of the whole hand: the palm centre's frame and the gesture channels.
struct HandPose {
  sim::Vec3d position{0.0, 0.0, 0.0};               ///< palm centre, world [m]
  sim::Quatd orientation = sim::Quatd::Identity();  ///< hand frame -> world
  double grip = 0.0;                                ///< [0, 1], see GestureChannels
  double point = 0.0;                               ///< [0, 1], see GestureChannels
};

/// World pose of one rigid part of the hand.
struct PartPose {
  sim::Vec3d position{0.0, 0.0, 0.0};               ///< centre of the part [m]
  sim::Quatd orientation = sim::Quatd::Identity();  ///< part frame -> world (a capsule's axis is local y)
};

/// Geometry and forward kinematics of the hand. Hand frame: the fingers point along -y when flat, the palm
/// faces +x (the side that pushes and towards which the fingers curl), the thumb is on the +z side, the wrist
/// at +y. Identity orientation is a hand hanging down, ready to push along +x.
class HandModel {
 public:
  static constexpr int kFingers = 5;                       ///< thumb, index, middle, ring, little
  static constexpr int kSegments = 3;                      ///< per finger
  static constexpr int kParts = 1 + kFingers * kSegments;  ///< palm first, then finger by finger
  static constexpr double kCurlRadians[kSegments] = {1.40, 1.65, 1.20};  ///< joint angles of a full curl

  /// an adult hand scaled by `scale` in (0.2, 5] (1: palm 8.4 x 10 x 2.6 cm, middle finger 9.2 cm)
  explicit HandModel(double scale = 1.0);

  /// the scale factor
  double scale() const { return m_scale; }
  /// world pose of every part, palm first, at `pose`
  std::array<PartPose, kParts> partPoses(const HandPose& pose) const;
  /// the parts as driven colliders ("hand_palm", "hand_index_1", ...) placed at `pose`
  std::vector<sim::ColliderDesc> colliders(const HandPose& pose) const;
  /// capsule radius of finger f's segments [m]
  double fingerRadius(int f) const { return m_radius[f] * m_scale; }
  /// length of segment s of finger f, joint to joint [m]
  double segmentLength(int f, int s) const { return m_length[f][s] * m_scale; }
  /// distance from the palm centre down to the tip of the straight middle finger [m]
  double reachBelowPalm() const;
  /// half extents of the palm box in the hand frame [m]
  sim::Vec3d palmHalfExtents() const { return m_palmHalf * m_scale; }

 private:
  double m_scale;
  sim::Vec3d m_palmHalf;                            // box half extents, hand frame
  std::array<sim::Vec3d, kFingers> m_base;          // first joint, hand frame
  std::array<sim::Quatd, kFingers> m_baseRotation;  // finger frame -> hand frame
  std::array<double, kFingers> m_radius;
  std::array<std::array<double, kSegments>, kFingers> m_length;
};

/// name of finger f: thumb, index, middle, ring, little
const char* fingerName(int f);

}  // namespace fp::input
