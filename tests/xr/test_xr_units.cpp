// The XR-free parts of the OpenXR mode: the off-axis projection, tracked joints to the hand's parts (both
// hands), the controller hand, the joint recording format and the easing of a hand whose tracking is lost.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/tracked_hands.h"
#include "input/joint_hand.h"
#include "input/joint_track.h"
#include "render/camera.h"

namespace fp {
namespace {

using input::HandJoints;
using input::HandModel;
using input::HandPose;
using input::HandSide;
using sim::Quatd;
using sim::Vec3d;

Eigen::Vector3f ndc(const render::Mat4& m, const Eigen::Vector3f& p) {
  const Eigen::Vector4f q = m * p.homogeneous();
  return q.head<3>() / q.w();
}

TEST(OffAxisProjection, SymmetricEqualsPerspective) {
  render::FieldOfView fov{-0.6f, 0.6f, 0.45f, -0.45f};
  const render::Mat4 a = render::offAxisPerspective(fov, 0.05f, 50.0f);
  const render::Mat4 b = render::perspective(0.9f, std::tan(0.6f) / std::tan(0.45f), 0.05f, 50.0f);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-5f);
}

TEST(OffAxisProjection, FrustumSidesMapToTheClipEdges) {
  const render::FieldOfView fov{-0.9f, 0.7f, 0.8f, -0.95f};  // an asymmetric eye, as headsets report
  const float n = 0.1f, f = 20.0f;
  const render::Mat4 m = render::offAxisPerspective(fov, n, f);
  for (float depth : {0.5f, 3.0f}) {
    EXPECT_NEAR(ndc(m, {depth * std::tan(fov.angleLeft), 0.0f, -depth}).x(), -1.0f, 1e-5f);
    EXPECT_NEAR(ndc(m, {depth * std::tan(fov.angleRight), 0.0f, -depth}).x(), 1.0f, 1e-5f);
    EXPECT_NEAR(ndc(m, {0.0f, depth * std::tan(fov.angleUp), -depth}).y(), 1.0f, 1e-5f);
    EXPECT_NEAR(ndc(m, {0.0f, depth * std::tan(fov.angleDown), -depth}).y(), -1.0f, 1e-5f);
  }
  EXPECT_NEAR(ndc(m, {0.0f, 0.0f, -n}).z(), -1.0f, 1e-5f);
  EXPECT_NEAR(ndc(m, {0.0f, 0.0f, -f}).z(), 1.0f, 1e-4f);
  // the view axis is off centre: right of centre because the left side is wider
  EXPECT_GT(ndc(m, {0.0f, 0.0f, -1.0f}).x(), 0.0f);
}

TEST(OffAxisProjection, ViewFromPoseLooksDownMinusZ) {
  const Eigen::Quaternionf turn(Eigen::AngleAxisf(0.5f * float(sim::kPi), Eigen::Vector3f::UnitY()));
  const render::Mat4 v = render::viewFromPose({1.0f, 1.6f, 0.0f}, turn);
  // turned 90 degrees left, the eye looks along world -x
  const Eigen::Vector4f p = v * Eigen::Vector4f(0.0f, 1.6f, 0.0f, 1.0f);
  EXPECT_NEAR(p.x(), 0.0f, 1e-6f);
  EXPECT_NEAR(p.z(), -1.0f, 1e-6f);
  const render::Mat4 look = render::lookAt({1.0f, 1.6f, 0.0f}, {0.0f, 1.6f, 0.0f}, Eigen::Vector3f::UnitY());
  EXPECT_LT((v - look).cwiseAbs().maxCoeff(), 1e-6f);
}

HandPose somePose() {
  HandPose p;
  p.position = Vec3d(0.1, 0.25, -0.05);
  p.orientation = Quatd(Eigen::AngleAxisd(0.4, Vec3d(0.3, 1.0, 0.2).normalized()));
  p.grip = 0.6;
  p.point = 0.3;
  return p;
}

TEST(JointHand, JointsOfTheModelGiveBackItsParts) {
  const HandModel model(1.1);
  const HandPose pose = somePose();
  const auto expected = model.partPoses(pose);
  const auto parts = input::partPosesFromJoints(input::jointsOfHandPose(model, pose, HandSide::Right));
  for (int k = 0; k < HandModel::kParts; ++k) {
    EXPECT_LT((parts[k].position - expected[k].position).norm(), 1e-9) << k;
    // capsules are symmetric about their axis: compare the axis, and the whole frame for the palm
    const Vec3d a = parts[k].orientation * Vec3d::UnitY(), b = expected[k].orientation * Vec3d::UnitY();
    EXPECT_LT((a - b).norm(), 1e-9) << k;
  }
  EXPECT_LT(parts[0].orientation.angularDistance(expected[0].orientation), 1e-9);
}

TEST(JointHand, CollidersFollowTheTrackedHandsSize) {
  for (double scale : {0.8, 1.0, 1.3}) {
    const HandModel model(scale);
    const HandJoints joints = input::jointsOfHandPose(model, somePose(), HandSide::Left);
    EXPECT_NEAR(input::trackedHandScale(joints), scale, 1e-9);
    const auto colliders = input::jointHandColliders(joints, HandSide::Left);
    ASSERT_EQ(colliders.size(), std::size_t(HandModel::kParts));
    EXPECT_EQ(colliders[0].name, "left_palm");
    EXPECT_EQ(colliders[5].name, "left_index_2");
    EXPECT_NEAR(colliders[0].halfExtents.y(), model.palmHalfExtents().y(), 1e-9);
    EXPECT_NEAR(colliders[0].halfExtents.x(), model.palmHalfExtents().x(), 1e-9);
    for (int f = 0; f < HandModel::kFingers; ++f) {
      for (int s = 0; s < HandModel::kSegments; ++s) {
        const sim::ColliderDesc& c = colliders[1 + 3 * f + s];
        EXPECT_TRUE(c.driven);
        EXPECT_EQ(c.shape, sim::ShapeType::Capsule);
        EXPECT_NEAR(c.radius, model.fingerRadius(f), 1e-12);
        EXPECT_NEAR(2.0 * c.halfLength, model.segmentLength(f, s), 1e-9);
      }
    }
  }
}

TEST(JointHand, LeftIsTheRightMirrored) {
  const HandModel model;
  HandPose pose;  // identity: fingers down, palms facing +x
  pose.grip = 0.5;
  const HandJoints right = input::jointsOfHandPose(model, pose, HandSide::Right);
  const HandJoints left = input::jointsOfHandPose(model, pose, HandSide::Left);
  for (int j = 0; j < input::kHandJoints; ++j) {
    const Vec3d r = right.joint[j].position, l = left.joint[j].position;
    EXPECT_LT((l - Vec3d(r.x(), r.y(), -r.z())).norm(), 1e-12) << input::jointName(j);
    // joint frames stay rotations with +z along the bone towards the wrist and +y out of the back of the hand
    EXPECT_NEAR(left.joint[j].orientation.norm(), 1.0, 1e-12);
    const Vec3d ly = left.joint[j].orientation * Vec3d::UnitY(),
                ry = right.joint[j].orientation * Vec3d::UnitY();
    EXPECT_LT((ly - Vec3d(ry.x(), ry.y(), -ry.z())).norm(), 1e-9) << input::jointName(j);
  }
  EXPECT_GT(right.joint[5].position.z(), 0.02);  // the right thumb on +z, the left on -z
  EXPECT_LT(left.joint[5].position.z(), -0.02);
  // the back of the flat hand (joint +y) faces -x: the palms push along +x
  EXPECT_NEAR((left.joint[0].orientation * Vec3d::UnitY()).x(), -1.0, 1e-9);
  EXPECT_NEAR((right.joint[0].orientation * Vec3d::UnitY()).x(), -1.0, 1e-9);
  // XR's convention for a real right hand: with the palm down and fingers forward (-z), the thumb is at -x
  HandPose palmDown;
  Eigen::Matrix3d down3;  // palm (+x) down, wrist (+y) towards +z, thumb side (+z) to -x
  down3.col(0) = -Vec3d::UnitY();
  down3.col(1) = Vec3d::UnitZ();
  down3.col(2) = -Vec3d::UnitX();
  palmDown.orientation = Quatd(down3);
  const HandJoints down = input::jointsOfHandPose(model, palmDown, HandSide::Right);
  EXPECT_LT(down.joint[15].position.z(), down.joint[0].position.z() - 0.05);  // fingers forward
  EXPECT_NEAR((down.joint[0].orientation * Vec3d::UnitY()).y(), 1.0, 1e-9);   // back of the hand up
  EXPECT_LT(down.joint[5].position.x(), down.joint[0].position.x() - 0.02);   // thumb at -x
}

TEST(JointHand, ControllerPointsAndMakesAFist) {
  const HandModel model;
  for (HandSide side : {HandSide::Left, HandSide::Right}) {
    const HandPose open = input::controllerHandPose(Vec3d(0, 1, 0), Quatd::Identity(), 0.0, 0.0, side);
    const HandJoints j = input::jointsOfHandPose(model, open, side);
    EXPECT_LT(j.joint[15].position.z(), j.joint[0].position.z() - 0.1);
    EXPECT_GT(j.joint[5].position.y(), j.joint[0].position.y() + 0.02) << "thumb up";
    const double palmX = (j.joint[0].orientation * Vec3d::UnitY()).x();  // back of the hand
    EXPECT_NEAR(palmX, side == HandSide::Right ? 1.0 : -1.0, 1e-9) << "palm faces the controller's middle";
    const HandPose point = input::controllerHandPose(Vec3d::Zero(), Quatd::Identity(), 0.0, 1.0, side);
    const auto curl = input::fingerCurl(point.grip, point.point);
    EXPECT_EQ(curl[1], 0.0);
    EXPECT_EQ(curl[2], 1.0);
    const HandPose fist = input::controllerHandPose(Vec3d::Zero(), Quatd::Identity(), 1.0, 1.0, side);
    EXPECT_EQ(input::fingerCurl(fist.grip, fist.point)[1], 1.0);
  }
}

input::JointFrame frameAt(double t, bool rightValid) {
  const HandModel model;
  input::JointFrame f;
  f.time = t;
  HandPose p = somePose();
  p.position.x() += t;
  f.hands[0] = input::jointsOfHandPose(model, p, HandSide::Left);
  f.hands[1] = input::jointsOfHandPose(model, p, HandSide::Right);
  f.hands[1].valid = rightValid;
  return f;
}

TEST(JointTrack, SaveLoadIsExactAndSamplesInterpolate) {
  input::JointTrack track;
  track.add(frameAt(0.0, true));
  track.add(frameAt(0.1, false));
  track.add(frameAt(0.2, true));
  const std::string path = (std::filesystem::temp_directory_path() / "fp_joint_track.csv").string();
  track.save(path);
  EXPECT_TRUE(input::JointTrack::isJointFile(path));
  const input::JointTrack back = input::JointTrack::load(path);
  ASSERT_EQ(back.frames().size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    for (int h = 0; h < 2; ++h) {
      EXPECT_EQ(back.frames()[i].hands[h].valid, track.frames()[i].hands[h].valid);
      for (int j = 0; j < input::kHandJoints; ++j) {
        EXPECT_EQ(back.frames()[i].hands[h].joint[j].position, track.frames()[i].hands[h].joint[j].position);
        EXPECT_EQ(back.frames()[i].hands[h].joint[j].orientation.coeffs(),
                  track.frames()[i].hands[h].joint[j].orientation.coeffs());
        EXPECT_EQ(back.frames()[i].hands[h].joint[j].radius, track.frames()[i].hands[h].joint[j].radius);
      }
    }
  }
  const input::JointFrame mid = back.sample(0.05);
  EXPECT_TRUE(mid.hands[0].valid);
  EXPECT_NEAR(mid.hands[0].joint[0].position.x(), somePose().position.x() + 0.05, 1e-12);
  EXPECT_TRUE(mid.hands[1].valid);  // valid at 0, lost at 0.1: as at 0
  EXPECT_FALSE(back.sample(0.15).hands[1].valid);
  EXPECT_TRUE(back.sample(9.0).hands[1].valid);
  std::filesystem::remove(path);
}

TEST(JointTrack, MalformedFilesNameTheLine) {
  const std::string path = (std::filesystem::temp_directory_path() / "fp_joint_bad.csv").string();
  auto expectError = [&](const std::string& text, const std::string& part) {
    std::ofstream(path) << text;
    try {
      input::JointTrack::load(path);
      FAIL() << "no error for " << part;
    } catch (const sim::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  const std::string header = "time,hand,joint,valid,px,py,pz,qw,qx,qy,qz,radius\n";
  expectError("time,px\n", ":1: expected header");
  expectError(header + "0,left,palm,1,0,0,0,1,0,0,0,0.01,7\n", ":2: expected 12 columns");
  expectError(header + "0,middle,palm,1,0,0,0,1,0,0,0,0.01\n", ":2: column 2");
  expectError(header + "0,left,elbow,1,0,0,0,1,0,0,0,0.01\n", ":2: column 3: unknown joint");
  expectError(header + "0,left,wrist,1,0,0,0,1,0,0,0,0.01\n", ":2: expected left joint palm");
  expectError(header + "0,left,palm,1,0,0,x,1,0,0,0,0.01\n", ":2: column 7: bad number");
  expectError(header + "0,left,palm,1,0,0,0,1,0,0,0,0.01\n", "left hand has 1 of 26 joints");
  std::filesystem::remove(path);
}

TEST(JointTrack, PutReplacesTheLastFrameOfTheSameTimeAndRecordedTimesSampleExactly) {
  input::JointTrack track;
  track.put(frameAt(0.0, false));
  track.put(frameAt(0.0, true));  // the same instant again: the later input wins
  track.put(frameAt(0.1, true));
  ASSERT_EQ(track.frames().size(), 2u);
  EXPECT_TRUE(track.frames()[0].hands[1].valid);
  EXPECT_THROW(track.put(frameAt(0.05, true)), sim::InputError);
  // between two recorded frames slerp and renormalisation could move the last bits: a recorded instant comes
  // back as recorded
  track.put(frameAt(0.2, true));
  const input::JointFrame at = track.sample(0.1);
  for (int h = 0; h < 2; ++h) {
    for (int j = 0; j < input::kHandJoints; ++j) {
      EXPECT_EQ(at.hands[h].joint[j].orientation.coeffs(),
                track.frames()[1].hands[h].joint[j].orientation.coeffs());
      EXPECT_EQ(at.hands[h].joint[j].position, track.frames()[1].hands[h].joint[j].position);
    }
  }
}

TEST(JointReplay, HandScriptsAreToldApartByTheirHeader) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string pose = (dir / "fp_script_pose.csv").string(),
                    joints = (dir / "fp_script_joints.csv").string(),
                    bad = (dir / "fp_script_bad.csv").string();
  std::ofstream(pose) << "time,px,py,pz,qw,qx,qy,qz,grip\n0,0,0.3,0,1,0,0,0,0\n";
  input::JointTrack track;
  track.add(frameAt(0.0, false));
  track.add(frameAt(0.1, true));
  track.save(joints);
  std::ofstream(bad) << input::JointTrack::header()
                     << "\n0,left,palm,1,0,0,0,1,0,0,0,0.01\n0,left,knee,1,0,0,0,1,0,0,0,0.01\n";
  EXPECT_FALSE(engine::JointReplay::ofScript(pose).has_value());
  EXPECT_FALSE(engine::JointReplay::ofScript("").has_value());
  const auto replay = engine::JointReplay::ofScript(joints);
  ASSERT_TRUE(replay.has_value());
  // the first frame's tracked hands size the hands: the left one here, the right one is not tracked
  EXPECT_TRUE(replay->first()[0].has_value());
  EXPECT_FALSE(replay->first()[1].has_value());
  try {
    engine::JointReplay::ofScript(bad);
    FAIL() << "no error for a malformed joint recording";
  } catch (const sim::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fp_script_bad.csv:3: column 3: unknown joint"), std::string::npos)
        << e.what();
  }
  for (const std::string& f : {pose, joints, bad})
    std::filesystem::remove(f);
}

TEST(TrackedHands, ReferencesAreTheTrackedHandsOrTheModelAtTheirSize) {
  sim::SceneDesc scene;
  scene.domain = sim::Aabb(Vec3d(-0.3, 0.0, -0.2), Vec3d(0.3, 0.4, 0.2));
  HandPose p = somePose();
  const input::HandJoints big = input::jointsOfHandPose(HandModel(1.5), p, HandSide::Right);
  engine::TrackedJoints first;
  first[1] = big;
  const auto refs = engine::trackedHandReferences(scene, first, 0.8);
  ASSERT_EQ(refs.size(), 2u);
  EXPECT_EQ(refs[0].first, HandSide::Left);
  EXPECT_EQ(refs[1].second.joint[15].position, big.joint[15].position);  // the tracked hand itself
  // the untracked left hand: the model at the tracked hand's size, not at --hand-size 0.8
  EXPECT_NEAR(input::trackedHandScale(refs[0].second), 1.5, 1e-9);
  EXPECT_NEAR(input::trackedHandScale(engine::trackedHandReferences(scene, {}, 0.8)[0].second), 0.8, 1e-9);
}

std::array<input::PartPose, HandModel::kParts> partsAt(const Vec3d& at) {
  HandPose p;
  p.position = at;
  return HandModel().partPoses(p);
}

TEST(HandPresence, LostHandRisesOutOfTheWaterAndEasesBack) {
  const double speed = 1.0, dt = 1.0 / 90.0, park = 0.5;
  input::HandPresence presence(park, speed);
  presence.update(partsAt(Vec3d(0, 0.1, 0)), dt);
  EXPECT_TRUE(presence.following());
  auto last = presence.parts();
  auto maxStep = [&](const auto& now) {
    double m = 0.0;
    for (int k = 0; k < HandModel::kParts; ++k)
      m = std::max(m, (now[k].position - last[k].position).norm());
    last = now;
    return m;
  };
  for (int frame = 0; frame < 90; ++frame) {
    const auto& now = presence.update(std::nullopt, dt);
    EXPECT_LE(maxStep(now), speed * dt + 1e-12);
  }
  double lowest = 1e9;
  for (const auto& p : presence.parts())
    lowest = std::min(lowest, p.position.y());
  EXPECT_NEAR(lowest, park, 1e-9);
  EXPECT_FALSE(presence.following());
  // reappears elsewhere: eases there at the bounded speed, then follows
  int frames = 0;
  while (!presence.following() && frames < 200) {
    const auto& now = presence.update(partsAt(Vec3d(0.2, 0.1, 0)), dt);
    EXPECT_LE(maxStep(now), speed * dt + 1e-12);
    ++frames;
  }
  EXPECT_TRUE(presence.following());
  EXPECT_GT(frames, 3);
  EXPECT_LT((presence.parts()[0].position - Vec3d(0.2, 0.1, 0)).norm(), 1e-12);
}

TEST(PartMotion, InterpolatesBetweenTheFramesEnds) {
  input::PartMotion motion;
  motion.set(partsAt(Vec3d(0, 0, 0)), partsAt(Vec3d(0.1, 0, 0)), 1.0, 1.1);
  EXPECT_NEAR(motion.sample(1.05)[3].position.x() - partsAt(Vec3d::Zero())[3].position.x(), 0.05, 1e-12);
  EXPECT_NEAR(motion.sample(5.0)[0].position.x(), 0.1, 1e-12);
}

// A batch of steps serving several frames (the headset while the solver lags) passes through every frame's
// pose in turn, evenly spaced, rather than cutting from the first to the last: a hand that went into the
// water and back out within the batch still pushes it. One pose through: the two-key motion, bit for bit.
TEST(PartMotion, PassesThroughEveryQueuedFramesPose) {
  input::PartMotion motion;
  const auto from = partsAt(Vec3d(0, 0, 0)), down = partsAt(Vec3d(0, -0.1, 0)),
             back = partsAt(Vec3d(0, 0, 0.1));
  motion.set(from, std::vector<input::PartMotion::Parts>{down, back}, 1.0, 1.2);
  EXPECT_NEAR(motion.sample(1.05)[0].position.y(), -0.05, 1e-12);
  EXPECT_NEAR(motion.sample(1.1)[0].position.y(), -0.1, 1e-12);
  EXPECT_NEAR(motion.sample(1.15)[0].position.y(), -0.05, 1e-12);
  EXPECT_NEAR(motion.sample(1.15)[0].position.z(), 0.05, 1e-12);
  EXPECT_NEAR(motion.sample(9.0)[0].position.z(), 0.1, 1e-12);
  input::PartMotion one, two;
  one.set(from, std::vector<input::PartMotion::Parts>{down}, 1.0, 1.2);
  two.set(from, down, 1.0, 1.2);
  for (double t : {0.9, 1.0, 1.0137, 1.1, 1.1999, 1.2, 1.3}) {
    for (int k = 0; k < input::HandModel::kParts; ++k) {
      EXPECT_EQ(one.sample(t)[k].position, two.sample(t)[k].position);
      EXPECT_EQ(one.sample(t)[k].orientation.coeffs(), two.sample(t)[k].orientation.coeffs());
    }
  }
}

}  // namespace
}  // namespace fp
