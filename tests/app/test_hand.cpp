// The virtual hand without a window: the cursor-to-hand mapping, the gesture finger curl, the hand's geometry
// and driven colliders (velocities that reach the next pose, so nothing tunnels), and the record/replay round
// trip of hand motion.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/app_session.h"
#include "input/hand_driver.h"
#include "input/hand_model.h"
#include "input/mouse_hand.h"
#include "input/pose_track.h"

using namespace fp;
using namespace fp::input;
using sim::Vec3d;

namespace {

ViewFrame tiltedView() {
  ViewFrame v;
  v.eye = Vec3d(0.3, 0.5, 1.2);
  v.forward = (Vec3d(0.0, 0.1, 0.0) - v.eye).normalized();
  v.right = v.forward.cross(Vec3d::UnitY()).normalized();
  v.up = v.right.cross(v.forward);
  v.fovY = 0.8;
  v.aspect = 16.0 / 9.0;
  return v;
}

}  // namespace

TEST(CursorMappingTest, CentreEdgesAndInverse) {
  const ViewFrame v = tiltedView();
  const int w = 1280, h = 720;
  const double depth = 0.9;
  // the centre of the window maps onto the view axis at the given depth
  const Vec3d centre = cursorToWorld(v, w / 2.0, h / 2.0, w, h, depth);
  EXPECT_LT((centre - (v.eye + v.forward * depth)).norm(), 1e-12);
  // the right edge lies depth * tan(fov/2) * aspect to the right, the top edge depth * tan(fov/2) up
  const Vec3d right = cursorToWorld(v, w, h / 2.0, w, h, depth);
  EXPECT_NEAR((right - centre).dot(v.right), depth * std::tan(0.4) * v.aspect, 1e-12);
  EXPECT_NEAR((right - centre).dot(v.up), 0.0, 1e-12);
  const Vec3d top = cursorToWorld(v, w / 2.0, 0.0, w, h, depth);
  EXPECT_NEAR((top - centre).dot(v.up), depth * std::tan(0.4), 1e-12);
  // every mapped point lies on the plane facing the camera, and projects back onto its pixel
  for (const auto& [x, y] : {std::pair{10.0, 20.0}, std::pair{900.0, 700.0}, std::pair{640.5, 100.25}}) {
    const Vec3d p = cursorToWorld(v, x, y, w, h, depth);
    EXPECT_NEAR((p - v.eye).dot(v.forward), depth, 1e-12);
    const Eigen::Vector2d back = worldToCursor(v, p, w, h);
    EXPECT_NEAR(back.x(), x, 1e-9);
    EXPECT_NEAR(back.y(), y, 1e-9);
  }
}

TEST(CursorMappingTest, MouseHandFollowsOnlyWhileSweepingWithBoundedSpeedAndDepth) {
  const ViewFrame v = tiltedView();
  HandPose start;
  start.position = v.eye + v.forward * 1.0;
  MouseHand hand(start);
  hand.maxSpeed = 2.0;
  // not sweeping: the cursor does not move the hand
  hand.update(v, 100, 100, 1280, 720, false, 0.0, 0.1);
  EXPECT_LT((hand.pose().position - start.position).norm(), 1e-12);
  // sweeping: it goes to the cursor's point on the plane at its depth, at most maxSpeed * dt per frame
  const Vec3d goal = cursorToWorld(v, 100, 100, 1280, 720, 1.0);
  hand.update(v, 100, 100, 1280, 720, true, 0.0, 0.01);
  EXPECT_NEAR((hand.pose().position - start.position).norm(), 0.02, 1e-12);
  for (int k = 0; k < 200; ++k)
    hand.update(v, 100, 100, 1280, 720, true, 0.0, 0.01);
  EXPECT_LT((hand.pose().position - goal).norm(), 1e-9);
  // the wheel moves it along the view direction, one depthStep a notch
  const Vec3d before = hand.pose().position;
  hand.update(v, 100, 100, 1280, 720, false, 2.0, 1.0);
  EXPECT_NEAR((hand.pose().position - before).dot(v.forward), 2 * hand.depthStep, 1e-12);
  // the palm (hand +x) faces the camera's horizontal view direction
  const Vec3d palm = hand.pose().orientation * Vec3d::UnitX();
  const Vec3d horizontal = Vec3d(v.forward.x(), 0.0, v.forward.z()).normalized();
  EXPECT_NEAR(palm.dot(horizontal), 1.0, 1e-12);
  // the box keeps it in
  hand.lo = Vec3d(-0.1, -0.1, -0.1);
  hand.hi = Vec3d(0.1, 0.1, 0.1);
  hand.update(v, 100, 100, 1280, 720, false, 0.0, 1.0);
  EXPECT_LE(hand.pose().position.cwiseAbs().maxCoeff(), 0.1 + 1e-12);
}

TEST(GestureTest, FingerCurlOfEachGesture) {
  const auto flat = fingerCurl(0.0, 0.0);
  const auto fist = fingerCurl(1.0, 0.0);
  const auto point = fingerCurl(1.0, 1.0);
  for (int f = 0; f < 5; ++f) {
    EXPECT_EQ(flat[f], 0.0) << fingerName(f);
    EXPECT_EQ(fist[f], 1.0) << fingerName(f);
    EXPECT_EQ(point[f], f == 1 ? 0.0 : 1.0) << fingerName(f);  // the index finger stays straight
  }
  EXPECT_EQ(fingerCurl(0.5, 0.0)[2], 0.5);
  EXPECT_EQ(parseGesture("fist"), Gesture::Fist);
  EXPECT_FALSE(parseGesture("wave"));
}

TEST(GestureTest, CurlIsAnimatedAtABoundedRate) {
  GestureAnimator a;
  a.rate = 4.0;
  a.setTarget(Gesture::Fist);
  a.advance(0.1);
  EXPECT_NEAR(a.channels().grip, 0.4, 1e-12);  // part way after 0.1 s
  a.advance(0.1);
  EXPECT_NEAR(a.channels().grip, 0.8, 1e-12);
  a.advance(1.0);
  EXPECT_EQ(a.channels().grip, 1.0);  // settles exactly, never overshoots
  a.setTarget(Gesture::Point);
  a.advance(0.125);
  EXPECT_NEAR(a.channels().point, 0.5, 1e-12);
  EXPECT_EQ(a.channels().grip, 1.0);
}

TEST(HandModelTest, AdultSizeAndCurlClosesTheFingersTowardsThePalm) {
  const HandModel model;
  HandPose flat;
  const auto open = model.partPoses(flat);
  ASSERT_EQ(open.size(), 16u);
  // flat: fingertips hang below the palm at adult length (about 17-20 cm wrist to middle fingertip)
  EXPECT_GT(model.reachBelowPalm() + 0.05, 0.17);
  EXPECT_LT(model.reachBelowPalm() + 0.05, 0.21);
  const int middleTip = 1 + 2 * HandModel::kSegments + 2;
  EXPECT_LT(open[middleTip].position.y(), -0.12);
  // a fist brings the middle fingertip up and in front of the palm (+x), within a hand's size of its centre
  HandPose fist;
  fist.grip = 1.0;
  const auto closed = model.partPoses(fist);
  EXPECT_GT(closed[middleTip].position.y(), open[middleTip].position.y() + 0.06);
  EXPECT_GT(closed[middleTip].position.x(), 0.0);
  EXPECT_LT(closed[middleTip].position.norm(), 0.1);
  // the colliders: a palm box and 15 driven capsules with the hand's radii
  const auto colliders = model.colliders(fist);
  ASSERT_EQ(colliders.size(), 16u);
  EXPECT_EQ(colliders[0].shape, sim::ShapeType::Box);
  for (std::size_t k = 1; k < colliders.size(); ++k) {
    EXPECT_EQ(colliders[k].shape, sim::ShapeType::Capsule);
    EXPECT_TRUE(colliders[k].driven);
    EXPECT_GE(colliders[k].radius, 0.006);
    EXPECT_LE(colliders[k].radius, 0.011);
  }
  // a scaled hand is a scaled copy
  const HandModel big(2.0);
  EXPECT_NEAR(big.partPoses(fist)[middleTip].position.norm(), 2.0 * closed[middleTip].position.norm(), 1e-12);
  EXPECT_THROW(HandModel(0.0), sim::InputError);
}

TEST(HandDriverTest, VelocitiesCarryEveryPartOntoTheNextPose) {
  sim::SceneDesc scene;
  scene.domain = sim::Aabb(Vec3d(-1, -1, -1), Vec3d(1, 1, 1));
  scene.params.particleRadius = 0.01;
  scene.fluid.push_back(
      sim::FluidBlock{sim::Aabb(Vec3d(-0.9, -0.9, -0.9), Vec3d(-0.8, -0.8, -0.8)), Vec3d::Zero()});
  HandPose start;
  start.position = Vec3d(0.0, 0.5, 0.0);
  const HandModel model;
  const HandDriver driver = HandDriver::attach(scene, model, start);
  EXPECT_EQ(driver.firstCollider(), 0u);
  ASSERT_EQ(scene.colliders.size(), 16u);
  sim::Simulation simulation(scene);
  // a fast sweep that also closes the fist and turns the hand
  PoseTrack track;
  PoseSample a;
  a.position = start.position;
  track.add(a);
  PoseSample b;
  b.time = 0.1;
  b.position = Vec3d(0.3, 0.4, 0.0);
  b.orientation = sim::Quatd(Eigen::AngleAxisd(0.5, Vec3d::UnitY()));
  b.grip = 1.0;
  track.add(b);
  const double h = 0.004;
  driver.apply(simulation, track, 0.0, h);
  const auto now = model.partPoses(handPoseOf(track.sample(0.0)));
  const auto next = model.partPoses(handPoseOf(track.sample(h)));
  for (int k = 0; k < HandModel::kParts; ++k) {
    const sim::ColliderState& c = simulation.colliders()[std::size_t(k)];
    EXPECT_LT((c.position - now[k].position).norm(), 1e-12);
    // position + velocity * h reaches the next pose: the boundary particles sweep the space in between
    EXPECT_LT((c.position + c.linearVelocity * h - next[k].position).norm(), 1e-9) << k;
    const sim::Quatd turned =
        sim::Quatd(Eigen::AngleAxisd(c.angularVelocity.norm() * h, c.angularVelocity.normalized())) *
        c.orientation;
    if (c.angularVelocity.norm() > 0) {
      EXPECT_LT(turned.angularDistance(next[k].orientation), 1e-9) << k;
    }
  }
}

TEST(HandRecordingTest, RecordReplayRoundTripKeepsPosesAndGestures) {
  PoseTrack track;
  for (int k = 0; k < 20; ++k) {
    PoseSample s;
    s.time = 0.05 * k + 0.0125 * (k % 3);
    s.position = Vec3d(0.01 * k, 0.3 - 0.002 * k * k, std::sin(0.3 * k) * 0.05);
    s.orientation = sim::Quatd(Eigen::AngleAxisd(0.1 * k, Vec3d(0.2, 1.0, 0.1).normalized()));
    s.grip = std::min(1.0, 0.07 * k);
    s.point = k > 10 ? 1.0 : 0.0;
    track.add(s);
  }
  const std::string path = (std::filesystem::path(::testing::TempDir()) / "fp_hand_roundtrip.csv").string();
  track.save(path);
  const PoseTrack back = PoseTrack::load(path);
  ASSERT_EQ(back.keys().size(), track.keys().size());
  for (std::size_t k = 0; k < track.keys().size(); ++k) {
    const PoseSample& a = track.keys()[k];
    const PoseSample& b = back.keys()[k];
    EXPECT_EQ(a.time, b.time);
    EXPECT_EQ(a.position, b.position);
    EXPECT_EQ(a.orientation.coeffs(), b.orientation.coeffs());
    EXPECT_EQ(a.grip, b.grip);
    EXPECT_EQ(a.point, b.point);
  }
  // replayed between the keys, the hand is where the original would be, fingers included
  const HandModel model;
  for (double t : {0.0, 0.031, 0.5, 0.77, 2.0}) {
    const auto p = model.partPoses(handPoseOf(track.sample(t)));
    const auto q = model.partPoses(handPoseOf(back.sample(t)));
    for (int k = 0; k < HandModel::kParts; ++k)
      EXPECT_EQ(p[k].position, q[k].position);
  }
  // a track without a point channel keeps the nine-column format the older recordings use
  PoseTrack plain;
  plain.add(PoseSample{});
  plain.save(path);
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "time,px,py,pz,qw,qx,qy,qz,grip");
}

TEST(HandRecordingTest, ShippedRecordingsLoad) {
  for (const char* name : {"push.csv", "scoop.csv", "splash.csv", "point_stir.csv", "push_x.csv"}) {
    const PoseTrack t = PoseTrack::load(std::string(FP_SOURCE_DIR) + "/assets/hands/" + name);
    EXPECT_GT(t.duration(), 0.5) << name;
  }
}
