#pragma once
/// A tracked hand as the 26 joints of XR_EXT_hand_tracking (in the project's own types, no OpenXR header),
/// and the articulated hand's parts driven from them: a capsule per phalanx from joint to joint with the
/// joints' radii and the palm box from the palm and wrist joints, sized by the tracked hand itself. Also the
/// reverse (joints of a HandModel pose, for controllers and generated recordings) and the easing of a hand
/// whose tracking is lost out of the water and back.

#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include "input/hand_model.h"
#include "sim/scene.h"
#include "sim/simulation.h"
#include "sim/types.h"

namespace fp::input {

/// Joints in XR_EXT_hand_tracking's order (XrHandJointEXT): palm, wrist, the thumb's metacarpal, proximal,
/// distal and tip, then index, middle, ring and little finger with metacarpal, proximal, intermediate,
/// distal and tip.
enum class HandJoint : int {
  Palm = 0,
  Wrist = 1,
  ThumbMetacarpal = 2,
  ThumbTip = 5,
  IndexMetacarpal = 6,
  MiddleMetacarpal = 11,
  MiddleTip = 15,
  LittleMetacarpal = 21,
  LittleTip = 25,
};
/// number of joints of a hand
constexpr int kHandJoints = 26;
/// "palm", "wrist", "thumb_metacarpal", ..., "little_tip" for joint index j in [0, 26)
const char* jointName(int j);
/// the index of the joint named `name`, or nothing
std::optional<int> parseJointName(std::string_view name);

/// Which hand.
enum class HandSide { Left = 0, Right = 1 };
/// "left" or "right"
const char* handSideName(HandSide side);

/// One joint as a runtime locates it: the joint frame's +z points along the bone away from the fingertip,
/// +y out of the back of the hand (the nail), x by the right-hand rule.
struct JointPose {
  sim::Vec3d position{0.0, 0.0, 0.0};               ///< [m], world
  sim::Quatd orientation = sim::Quatd::Identity();  ///< joint -> world
  double radius = 0.01;                             ///< distance to the skin [m], > 0
};

/// The joints of one hand at one instant.
struct HandJoints {
  bool valid = false;                        ///< tracked: the poses below are meaningful
  std::array<JointPose, kHandJoints> joint;  ///< in HandJoint order
};

/// the world poses of the HandModel's parts (palm, then finger by finger, three segments each) placed on the
/// tracked joints: each phalanx centred between its two joints with its axis along them, the palm on the
/// palm joint; the joints must be valid
std::array<PartPose, HandModel::kParts> partPosesFromJoints(const HandJoints& joints);

/// The hand's colliders sized from one tracked frame (`reference`): capsules as long as the bones, with the
/// mean radius of their two joints, the palm box as long as twice the wrist-palm distance, as wide as the
/// knuckles and as thick as the palm joint's radius; placed on `reference`. Names "left_palm",
/// "right_index_2", ... ; driven colliders in the HandModel's part order.
std::vector<sim::ColliderDesc> jointHandColliders(const HandJoints& reference, HandSide side);

/// The joints of the model hand at `pose`; the left hand is the model mirrored across its hand frame's
/// thumb axis (so both palms face +x at identity and the left thumb is on the -z side).
HandJoints jointsOfHandPose(const HandModel& model, const HandPose& pose, HandSide side);

/// The hand pose of a controller held in `side`'s hand: the palm centre on the grip pose (XR grip frame: -z
/// along the fist's tube, the palm facing -x in the right hand and +x in the left), the fingers forward;
/// squeeze [0, 1] curls the other fingers and trigger [0, 1] the index: squeeze alone points, both make a
/// fist. Give it to jointsOfHandPose with the same side.
HandPose controllerHandPose(const sim::Vec3d& gripPosition, const sim::Quatd& gripOrientation, double trigger,
                            double squeeze, HandSide side);

/// Size of a tracked hand relative to HandModel(1): wrist to middle fingertip over the model's 19 cm.
double trackedHandScale(const HandJoints& joints);

/// The motion of a hand's parts over one frame, from the pose at the frame's start to the pose at its end,
/// interpolated across the solver steps the way HandDriver interpolates a pose track, so a fast hand never
/// jumps through the water between steps. A batch of steps that serves several displayed frames (the
/// headset while the solver lags) passes through each frame's pose in turn, evenly spaced in time.
class PartMotion {
 public:
  using Parts = std::array<PartPose, HandModel::kParts>;
  /// the parts move from `from` at simulated time t0 to `to` at t1 (> t0) [s]
  void set(const Parts& from, const Parts& to, double t0, double t1);
  /// the parts move from `from` at simulated time t0 through `through` (at least one), the last at t1 (> t0)
  /// and the others evenly spaced between [s]
  void set(const Parts& from, const std::vector<Parts>& through, double t0, double t1);
  /// the parts at time t (clamped to [t0, t1]): positions linear, orientations slerp, key to key
  Parts sample(double t) const;
  /// sets the colliders first.. first+15 of `simulation` at its time with the velocities that reach the pose
  /// at time + h (h > 0 [s])
  void apply(sim::Simulation& simulation, std::size_t first, double h) const;

 private:
  std::vector<Parts> m_keys = std::vector<Parts>(2);  // from, then the poses it passes through
  double m_t0 = 0.0;
  double m_t1 = 1.0;
};

/// Keeps a hand's parts out of trouble when tracking comes and goes: while tracked they follow the joints;
/// when tracking is lost they rise from where they were to `parkHeight` at a bounded speed (out of the water,
/// never through it); when the hand reappears they move to it at the same bounded speed, then follow again.
class HandPresence {
 public:
  /// world height the lost hand rises to [m] (above the water), speed of easing [m/s] (> 0)
  HandPresence(double parkHeight, double easeSpeed) : m_parkHeight(parkHeight), m_speed(easeSpeed) {}
  /// the parts for a frame of `dt` [s] (>= 0) with the tracked parts, or nothing when tracking is lost; the
  /// first call with parts places the hand there at once
  const std::array<PartPose, HandModel::kParts>& update(
      const std::optional<std::array<PartPose, HandModel::kParts>>& tracked, double dt);
  /// places the hand at `parts` without following: the next tracked frame is eased to, not jumped to
  void park(const std::array<PartPose, HandModel::kParts>& parts) {
    m_parts = parts;
    m_placed = true;
    m_following = false;
  }
  /// the current parts
  const std::array<PartPose, HandModel::kParts>& parts() const { return m_parts; }
  /// true while the parts follow the tracked hand exactly (false while lost or easing back)
  bool following() const { return m_following; }
  /// true once a tracked frame placed the hand
  bool placed() const { return m_placed; }

 private:
  double m_parkHeight;
  double m_speed;
  bool m_placed = false;
  bool m_following = false;
  std::array<PartPose, HandModel::kParts> m_parts{};
};

}  // namespace fp::input
