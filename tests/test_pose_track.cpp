#include "input/pose_track.h"
#include "tests/temp_path.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace fp::input {
namespace {

using sim::kPi;
using sim::Quatd;
using sim::Vec3d;

Quatd rotZ(double degrees) {
  return Quatd(Eigen::AngleAxisd(degrees * kPi / 180.0, Vec3d::UnitZ()));
}
Quatd rotX(double degrees) {
  return Quatd(Eigen::AngleAxisd(degrees * kPi / 180.0, Vec3d::UnitX()));
}

PoseSample key(double time, const Vec3d& position, const Quatd& orientation, double grip) {
  PoseSample k;
  k.time = time;
  k.position = position;
  k.orientation = orientation;
  k.grip = grip;
  return k;
}

void expectVecNear(const Vec3d& actual, const Vec3d& expected, double tol = 1e-12) {
  EXPECT_NEAR(actual.x(), expected.x(), tol);
  EXPECT_NEAR(actual.y(), expected.y(), tol);
  EXPECT_NEAR(actual.z(), expected.z(), tol);
}

/// Three keys: a 2 s segment that moves, rotates 90 degrees about z and closes the grip, then a 1 s segment
/// that only moves along z and half opens the grip.
PoseTrack threeKeyTrack() {
  PoseTrack track;
  track.add(key(0.0, Vec3d(0.0, 0.0, 0.0), Quatd::Identity(), 0.0));
  track.add(key(2.0, Vec3d(1.0, 2.0, -4.0), rotZ(90.0), 1.0));
  track.add(key(3.0, Vec3d(1.0, 2.0, 0.0), rotZ(90.0), 0.5));
  return track;
}

class PoseTrackTest : public ::testing::Test {
 protected:
  void TearDown() override {
    for (const std::string& path : m_files) {
      std::remove(path.c_str());
    }
  }

  /// A path private to this test and process, removed after the test.
  std::string tempPath(const std::string& name) {
    std::string path = test::tempPath(name);
    m_files.push_back(path);
    return path;
  }

  std::string writeFile(const std::string& name, const std::string& text) {
    const std::string path = tempPath(name);
    std::ofstream(path) << text;
    return path;
  }

  static std::string loadError(const std::string& path) {
    try {
      PoseTrack::load(path);
    } catch (const sim::InputError& e) {
      return e.what();
    }
    return "(no error)";
  }

 private:
  std::vector<std::string> m_files;
};

constexpr const char* kHeader = "time,px,py,pz,qw,qx,qy,qz,grip\n";

TEST_F(PoseTrackTest, DurationIsTimeOfLastKey) {
  PoseTrack track;
  EXPECT_EQ(track.duration(), 0.0);
  track.add(key(0.5, Vec3d::Zero(), Quatd::Identity(), 0.0));
  EXPECT_EQ(track.duration(), 0.5);
  EXPECT_EQ(threeKeyTrack().duration(), 3.0);
}

TEST_F(PoseTrackTest, SampleAtKeysReturnsKeysExactly) {
  const PoseTrack track = threeKeyTrack();
  for (const PoseSample& k : track.keys()) {
    const PoseSample s = track.sample(k.time);
    EXPECT_EQ(s.time, k.time);
    EXPECT_EQ(s.position, k.position);
    EXPECT_EQ(s.orientation.coeffs(), k.orientation.coeffs());
    EXPECT_EQ(s.grip, k.grip);
  }
}

TEST_F(PoseTrackTest, SampleAtMidpointsInterpolatesLinearly) {
  const PoseTrack track = threeKeyTrack();
  const PoseSample a = track.sample(1.0);
  EXPECT_EQ(a.time, 1.0);
  expectVecNear(a.position, Vec3d(0.5, 1.0, -2.0));
  EXPECT_NEAR(a.grip, 0.5, 1e-12);
  const PoseSample b = track.sample(2.5);
  expectVecNear(b.position, Vec3d(1.0, 2.0, -2.0));
  EXPECT_NEAR(b.grip, 0.75, 1e-12);
  // A quarter of the way into the first segment.
  const PoseSample c = track.sample(0.5);
  expectVecNear(c.position, Vec3d(0.25, 0.5, -1.0));
  EXPECT_NEAR(c.grip, 0.25, 1e-12);
}

TEST_F(PoseTrackTest, SlerpMidpointOf90DegreeRotationIs45Degrees) {
  const PoseSample mid = threeKeyTrack().sample(1.0);
  EXPECT_NEAR(mid.orientation.norm(), 1.0, 1e-12);
  EXPECT_NEAR(mid.orientation.angularDistance(rotZ(45.0)), 0.0, 1e-12);
  const double h = std::sqrt(0.5);
  expectVecNear(mid.orientation * Vec3d::UnitX(), Vec3d(h, h, 0.0));
  // Slerp has constant angular speed: a quarter of the segment is a quarter of the angle.
  EXPECT_NEAR(threeKeyTrack().sample(0.5).orientation.angularDistance(rotZ(22.5)), 0.0, 1e-12);
}

TEST_F(PoseTrackTest, SlerpTakesShortestPath) {
  // -q is the same rotation as q: the midpoint must still be 45 degrees, not a detour through 225.
  PoseTrack negated;
  negated.add(key(0.0, Vec3d::Zero(), Quatd::Identity(), 0.0));
  negated.add(key(1.0, Vec3d::Zero(), Quatd(-rotZ(90.0).coeffs()), 0.0));
  EXPECT_NEAR(negated.sample(0.5).orientation.angularDistance(rotZ(45.0)), 0.0, 1e-12);
  expectVecNear(negated.sample(0.5).angularVelocity, Vec3d(0.0, 0.0, kPi / 2.0));

  // A 270-degree key is reached by turning -90 degrees.
  PoseTrack wide;
  wide.add(key(0.0, Vec3d::Zero(), Quatd::Identity(), 0.0));
  wide.add(key(1.0, Vec3d::Zero(), rotZ(270.0), 0.0));
  EXPECT_NEAR(wide.sample(0.5).orientation.angularDistance(rotZ(-45.0)), 0.0, 1e-12);
  expectVecNear(wide.sample(0.5).angularVelocity, Vec3d(0.0, 0.0, -kPi / 2.0));
}

TEST_F(PoseTrackTest, ClampsAtEndsWithZeroVelocity) {
  const PoseTrack track = threeKeyTrack();
  const PoseSample before = track.sample(-1.0);
  EXPECT_EQ(before.time, -1.0);
  EXPECT_EQ(before.position, track.keys().front().position);
  EXPECT_EQ(before.orientation.coeffs(), track.keys().front().orientation.coeffs());
  EXPECT_EQ(before.grip, 0.0);
  EXPECT_EQ(before.linearVelocity, Vec3d::Zero());
  EXPECT_EQ(before.angularVelocity, Vec3d::Zero());

  const PoseSample after = track.sample(10.0);
  EXPECT_EQ(after.position, track.keys().back().position);
  EXPECT_EQ(after.orientation.coeffs(), track.keys().back().orientation.coeffs());
  EXPECT_EQ(after.grip, 0.5);
  EXPECT_EQ(after.linearVelocity, Vec3d::Zero());
  EXPECT_EQ(after.angularVelocity, Vec3d::Zero());
}

TEST_F(PoseTrackTest, FewerThanTwoKeysGiveZeroVelocity) {
  PoseTrack empty;
  const PoseSample none = empty.sample(1.0);
  EXPECT_EQ(none.position, Vec3d::Zero());
  EXPECT_EQ(none.linearVelocity, Vec3d::Zero());

  PoseTrack single;
  single.add(key(1.0, Vec3d(1.0, 2.0, 3.0), rotZ(30.0), 0.3));
  for (double t : {0.0, 1.0, 2.0}) {
    const PoseSample s = single.sample(t);
    EXPECT_EQ(s.position, Vec3d(1.0, 2.0, 3.0));
    EXPECT_EQ(s.grip, 0.3);
    EXPECT_EQ(s.linearVelocity, Vec3d::Zero());
    EXPECT_EQ(s.angularVelocity, Vec3d::Zero());
  }
}

TEST_F(PoseTrackTest, LinearVelocityIsSegmentDisplacementOverDuration) {
  const PoseTrack track = threeKeyTrack();
  // First segment: (1, 2, -4) m in 2 s.
  expectVecNear(track.sample(0.0).linearVelocity, Vec3d(0.5, 1.0, -2.0));
  expectVecNear(track.sample(1.3).linearVelocity, Vec3d(0.5, 1.0, -2.0));
  // A key belongs to the segment it starts; the last key to the last segment: (0, 0, 4) m in 1 s.
  expectVecNear(track.sample(2.0).linearVelocity, Vec3d(0.0, 0.0, 4.0));
  expectVecNear(track.sample(3.0).linearVelocity, Vec3d(0.0, 0.0, 4.0));
}

TEST_F(PoseTrackTest, AngularVelocityIsWorldFrameAxisTimesAngleOverDuration) {
  const PoseTrack track = threeKeyTrack();
  // 90 degrees about z in 2 s.
  expectVecNear(track.sample(1.0).angularVelocity, Vec3d(0.0, 0.0, kPi / 4.0));
  expectVecNear(track.sample(2.5).angularVelocity, Vec3d::Zero());

  // Start tilted 90 degrees about x, then turn 90 degrees about the WORLD z axis in 0.5 s: the body-frame
  // axis would be -y, the world-frame one is z.
  PoseTrack tilted;
  tilted.add(key(0.0, Vec3d::Zero(), rotX(90.0), 0.0));
  tilted.add(key(0.5, Vec3d::Zero(), rotZ(90.0) * rotX(90.0), 0.0));
  expectVecNear(tilted.sample(0.25).angularVelocity, Vec3d(0.0, 0.0, kPi));
}

TEST_F(PoseTrackTest, AddNormalisesOrientation) {
  PoseTrack track;
  track.add(key(0.0, Vec3d::Zero(), Quatd(2.0, 0.0, 0.0, 0.0), 0.0));
  track.add(key(1.0, Vec3d::Zero(), Quatd(0.0, 0.0, 0.0, 3.0), 0.0));
  EXPECT_EQ(track.keys()[0].orientation.coeffs(), Quatd::Identity().coeffs());
  EXPECT_NEAR(track.keys()[1].orientation.norm(), 1.0, 1e-15);
  EXPECT_EQ(track.keys()[1].orientation.z(), 1.0);
}

TEST_F(PoseTrackTest, AddRejectsNonIncreasingTime) {
  PoseTrack track;
  track.add(key(1.0, Vec3d::Zero(), Quatd::Identity(), 0.0));
  EXPECT_THROW(track.add(key(1.0, Vec3d::Zero(), Quatd::Identity(), 0.0)), sim::InputError);
  EXPECT_THROW(track.add(key(0.5, Vec3d::Zero(), Quatd::Identity(), 0.0)), sim::InputError);
  EXPECT_EQ(track.keys().size(), 1u);
  track.add(key(1.5, Vec3d::Zero(), Quatd::Identity(), 0.0));
  EXPECT_EQ(track.keys().size(), 2u);
}

TEST_F(PoseTrackTest, AddRejectsNonFiniteValuesAndZeroQuaternion) {
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  PoseTrack track;
  EXPECT_THROW(track.add(key(nan, Vec3d::Zero(), Quatd::Identity(), 0.0)), sim::InputError);
  EXPECT_THROW(track.add(key(0.0, Vec3d(0.0, nan, 0.0), Quatd::Identity(), 0.0)), sim::InputError);
  EXPECT_THROW(track.add(key(0.0, Vec3d::Zero(), Quatd(1.0, inf, 0.0, 0.0), 0.0)), sim::InputError);
  EXPECT_THROW(track.add(key(0.0, Vec3d::Zero(), Quatd::Identity(), inf)), sim::InputError);
  EXPECT_THROW(track.add(key(0.0, Vec3d::Zero(), Quatd(0.0, 0.0, 0.0, 0.0), 0.0)), sim::InputError);
  EXPECT_TRUE(track.keys().empty());
}

TEST_F(PoseTrackTest, SaveLoadRoundTripIsExact) {
  PoseTrack track;
  track.add(key(0.1, Vec3d(1.0 / 3.0, -2.0 / 7.0, 1e-300), Quatd::Identity(), 0.0));
  track.add(key(0.1 + 1.0 / 3.0, Vec3d(12345.678901234567, -0.0, kPi),
                Quatd(Eigen::AngleAxisd(0.7, Vec3d(1.0, 2.0, 3.0).normalized())), 2.0 / 3.0));
  track.add(key(7.0, Vec3d(-1e-9, 5e-324, 1.0),
                Quatd(Eigen::AngleAxisd(-2.9, Vec3d(-0.3, 0.1, 0.9).normalized())), 1.0));
  const std::string path = tempPath("round_trip.csv");
  track.save(path);
  const PoseTrack loaded = PoseTrack::load(path);
  ASSERT_EQ(loaded.keys().size(), track.keys().size());
  for (size_t i = 0; i < track.keys().size(); ++i) {
    const PoseSample& a = track.keys()[i];
    const PoseSample& b = loaded.keys()[i];
    EXPECT_EQ(b.time, a.time) << "key " << i;
    EXPECT_EQ(b.position, a.position) << "key " << i;
    EXPECT_EQ(b.orientation.coeffs(), a.orientation.coeffs()) << "key " << i;
    EXPECT_EQ(b.grip, a.grip) << "key " << i;
  }
  // Saving the loaded track reproduces the file byte for byte.
  const std::string again = tempPath("round_trip_again.csv");
  loaded.save(again);
  std::stringstream first, second;
  first << std::ifstream(path).rdbuf();
  second << std::ifstream(again).rdbuf();
  EXPECT_EQ(first.str(), second.str());
  EXPECT_EQ(first.str().rfind(kHeader, 0), 0u);
}

TEST_F(PoseTrackTest, LoadErrorsNameFileAndLine) {
  struct Case {
    const char* name;
    std::string text;
    const char* where;
    const char* what;
  };
  const Case cases[] = {
      {"bad_header.csv", "t,x,y,z\n0,0,0,0,1,0,0,0,0\n", ":1:", "header"},
      {"empty.csv", "", ":1:", "header"},
      {"columns.csv", std::string(kHeader) + "0,0,0,0,1,0,0,0,0\n1,0,0,0,1,0,0,0\n", ":3:", "columns"},
      {"number.csv", std::string(kHeader) + "0,0,abc,0,1,0,0,0,0\n", ":2:", "abc"},
      {"empty_field.csv", std::string(kHeader) + "0,0,,0,1,0,0,0,0\n", ":2:", "bad number"},
      {"nan.csv", std::string(kHeader) + "0,nan,0,0,1,0,0,0,0\n", ":2:", "not finite"},
      {"time.csv", std::string(kHeader) + "0,0,0,0,1,0,0,0,0\n1,0,0,0,1,0,0,0,0\n\n1,0,0,0,1,0,0,0,0\n",
       ":5:", "not after"},
  };
  for (const Case& c : cases) {
    const std::string path = writeFile(c.name, c.text);
    const std::string message = loadError(path);
    EXPECT_NE(message.find(path + c.where), std::string::npos) << c.name << ": " << message;
    EXPECT_NE(message.find(c.what), std::string::npos) << c.name << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << c.name << ": " << message;
  }
}

TEST_F(PoseTrackTest, LoadMissingFileNamesIt) {
  const std::string path = tempPath("does_not_exist.csv");
  const std::string message = loadError(path);
  EXPECT_NE(message.find(path), std::string::npos) << message;
}

TEST_F(PoseTrackTest, LoadAcceptsCrLfAndBlankLines) {
  const std::string path = writeFile(
      "crlf.csv", "time,px,py,pz,qw,qx,qy,qz,grip\r\n0,1,2,3,1,0,0,0,0\r\n\r\n1, 4,5,6,1,0,0,0,1\r\n");
  const PoseTrack track = PoseTrack::load(path);
  ASSERT_EQ(track.keys().size(), 2u);
  EXPECT_EQ(track.keys()[1].position, Vec3d(4.0, 5.0, 6.0));
}

TEST_F(PoseTrackTest, SaveToUnwritablePathThrows) {
  EXPECT_THROW(threeKeyTrack().save("/nonexistent-directory/track.csv"), sim::InputError);
}

TEST_F(PoseTrackTest, PushXRecordingMatchesItsDescription) {
  const PoseTrack track = PoseTrack::load(std::string(FP_SOURCE_DIR) + "/assets/hands/push_x.csv");
  EXPECT_EQ(track.duration(), 3.0);
  EXPECT_GE(track.keys().size(), 8u);
  EXPECT_EQ(track.sample(0.0).position, Vec3d(-0.1, 0.25, 0.0));
  EXPECT_EQ(track.sample(0.0).grip, 0.0);
  expectVecNear(track.sample(0.5).position, Vec3d(-0.1, 0.12, 0.0));
  expectVecNear(track.sample(2.0).position, Vec3d(0.15, 0.12, 0.0));
  expectVecNear(track.sample(3.0).position, Vec3d(0.15, 0.3, 0.0));
  EXPECT_EQ(track.sample(3.0).grip, 1.0);
  // The push phase moves along +x only, at the depth of the dip.
  for (double t = 0.5; t <= 2.0; t += 0.125) {
    const PoseSample s = track.sample(t);
    EXPECT_NEAR(s.position.y(), 0.12, 1e-12) << "t=" << t;
    EXPECT_GE(s.linearVelocity.x(), 0.0) << "t=" << t;
  }
}

}  // namespace
}  // namespace fp::input
