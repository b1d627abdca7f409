// Writes the two joint recordings of assets/hands/ (deterministic: run it again and the files do not change):
//   fp_make_joint_recordings assets/hands
// two_hands_push.csv: both hands, palms facing +x and thumbs towards each other, dip into the hand tank's
// water and push 27 cm along +x at 0.45 m/s, then lift out (assets/hands/push.csv with two hands).
// two_hands_lost.csv: the same push; the left hand closes into a fist under water and the right hand's
// tracking is lost from 0.7 s to 0.9 s, mid-push.
#include <cmath>
#include <cstdio>
#include <string>

#include "input/hand_driver.h"
#include "input/joint_track.h"
#include "input/pose_track.h"

namespace {

using fp::input::HandSide;

fp::input::PoseTrack pushTrack(double z, bool fist) {
  fp::input::PoseTrack t;
  auto key = [&](double time, double x, double y, double grip) {
    fp::input::PoseSample s;
    s.time = time;
    s.position = fp::sim::Vec3d(x, y, z);
    s.grip = grip;
    t.add(s);
  };
  key(0.0, -0.16, 0.34, 0.0);
  key(0.3, -0.16, 0.22, 0.0);
  key(0.4, -0.15, 0.22, 0.0);
  key(1.0, 0.12, 0.22, fist ? 1.0 : 0.0);
  key(1.2, 0.14, 0.22, fist ? 1.0 : 0.0);
  key(1.6, 0.14, 0.34, 0.5);
  return t;
}

/// 1e-5 m and 1e-6 resolution keeps the files small; the orientations are renormalised when read
double round(double v, double perUnit) {
  return std::round(v * perUnit) / perUnit;
}

void write(const std::string& path, bool lost) {
  const fp::input::HandModel model;
  const fp::input::PoseTrack left = pushTrack(0.09, lost), right = pushTrack(-0.09, false);
  fp::input::JointTrack track;
  for (int frame = 0; frame <= 48; ++frame) {  // 30 Hz for 1.6 s
    fp::input::JointFrame f;
    f.time = frame / 30.0;
    f.hands[0] =
        fp::input::jointsOfHandPose(model, fp::input::handPoseOf(left.sample(f.time)), HandSide::Left);
    f.hands[1] =
        fp::input::jointsOfHandPose(model, fp::input::handPoseOf(right.sample(f.time)), HandSide::Right);
    f.time = round(f.time, 1e6);
    if (lost && f.time > 0.69 && f.time < 0.91)
      f.hands[1].valid = false;
    for (auto& hand : f.hands) {
      for (auto& j : hand.joint) {
        j.position = j.position.unaryExpr([](double v) { return round(v, 1e5); });
        j.orientation.coeffs() = j.orientation.coeffs().unaryExpr([](double v) { return round(v, 1e6); });
        j.radius = round(j.radius, 1e5);
      }
    }
    track.add(f);
  }
  track.save(path);
  std::printf("%s: %zu frames\n", path.c_str(), track.frames().size());
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "assets/hands";
  write(dir + "/two_hands_push.csv", false);
  write(dir + "/two_hands_lost.csv", true);
  return 0;
}
