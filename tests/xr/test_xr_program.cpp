// engine/xr_program against the test runtime, with the core validation layer on: the session lifecycle (begin
// on READY, recreate after LOSS_PENDING, end on STOPPING, quit on EXITING), frames with both eyes drawn,
// tracked hands and the controller fallback.
#include <gtest/gtest.h>

#include <filesystem>

#include "engine/xr_program.h"
#include "input/joint_track.h"
#include "tests/xr/xr_test_env.h"

namespace fp {
namespace {

std::string dirOf(const char* test) {
  return (std::filesystem::temp_directory_path() / "fp_xr_program_test" / test).string();
}

class XrProgramTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    m_validation = test::useTestRuntime(dirOf(name.c_str()));
    m_stats = dirOf(name.c_str()) + "/stats.txt";
    std::filesystem::remove(m_stats);
    setenv("FP_XR_STATS", m_stats.c_str(), 1);
    setenv("FP_XR_VIRTUAL_TIME", "1", 1);
  }
  void TearDown() override { EXPECT_EQ(test::validationMessages(m_validation), ""); }

  engine::GlxBinding binding() const { return m_gl.binding(); }

  /// runs frames until the program exits or `limit` frames; counts recreations
  int run(engine::XrProgram& xr, int limit, int& recreated, std::vector<engine::XrHands>* hands = nullptr) {
    int frames = 0;
    for (int k = 0; k < 10 * limit && frames < limit; ++k) {
      const engine::XrLifecycle l = xr.pollEvents();
      if (l == engine::XrLifecycle::Exit)
        break;
      if (l == engine::XrLifecycle::Recreate) {
        ++recreated;
        xr.createSession(binding());
        continue;
      }
      if (l != engine::XrLifecycle::Running)
        continue;
      const auto timing = xr.beginFrame();
      EXPECT_NEAR(timing.period, 1.0 / 90.0, 1e-9);
      const auto eyes = xr.locateEyes();
      EXPECT_NEAR(eyes[1].position.x() - eyes[0].position.x(), 0.064f, 1e-5f);
      if (timing.shouldRender) {
        for (int eye = 0; eye < 2; ++eye) {
          xr.acquireEye(eye);
          glViewport(0, 0, eyes[eye].width, eyes[eye].height);
          glClearColor(0.1f, 0.2f, 0.3f, 1.0f);
          glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
          xr.releaseEye(eye);
        }
      }
      const engine::XrHands h = xr.locateHands();
      if (hands)
        hands->push_back(h);
      xr.endFrame(timing.shouldRender, 0.05f, 50.0f);
      ++frames;
    }
    return frames;
  }

  test::GlxContext m_gl;
  std::string m_validation;
  std::string m_stats;
};

TEST_F(XrProgramTest, LifecycleSurvivesLossPendingAndExits) {
  setenv("FP_XR_EVENTS", "5:loss_pending,14:exit", 1);
  setenv("FP_XR_SIZE", "96,80", 1);
  std::string error;
  if (!m_gl.create(error))
    GTEST_SKIP() << error;
  engine::XrProgram xr("fp_test_xr_program");
  EXPECT_EQ(xr.recommendedSize()[0], 96);
  xr.createSession(binding());
  EXPECT_TRUE(xr.stageSpace());
  int recreated = 0;
  const int frames = run(xr, 100, recreated);
  EXPECT_EQ(recreated, 1);
  EXPECT_FALSE(xr.hasSession());
  EXPECT_GE(frames, 12);
  EXPECT_LT(frames, 20);
  EXPECT_EQ(test::runtimeStat(m_stats, "sessions"), 2);
  EXPECT_EQ(test::runtimeStat(m_stats, "submitted"), frames);
  EXPECT_EQ(test::runtimeStat(m_stats, "ended"), 1);
}

TEST_F(XrProgramTest, RequestedExitEndsTheSession) {
  std::string error;
  if (!m_gl.create(error))
    GTEST_SKIP() << error;
  engine::XrProgram xr("fp_test_xr_program");
  xr.createSession(binding());
  int recreated = 0;
  EXPECT_EQ(run(xr, 3, recreated), 3);
  xr.requestExit();
  EXPECT_EQ(run(xr, 100, recreated), 0);
  EXPECT_FALSE(xr.hasSession());
}

TEST_F(XrProgramTest, TrackedHandsAndTheControllerFallback) {
  const std::string joints = std::string(FP_SOURCE_DIR) + "/assets/hands/two_hands_lost.csv";
  setenv("FP_XR_HANDS", joints.c_str(), 1);
  setenv("FP_XR_EVENTS", "3:menu", 1);
  std::string error;
  if (!m_gl.create(error))
    GTEST_SKIP() << error;
  const input::JointTrack track = input::JointTrack::load(joints);
  {
    engine::XrProgram xr("fp_test_xr_program");
    xr.createSession(binding());
    std::vector<engine::XrHands> hands;
    int recreated = 0;
    run(xr, 90, recreated, &hands);
    ASSERT_EQ(hands.size(), 90u);
    int lost = 0;
    EXPECT_FALSE(hands[0].joints[0].has_value()) << "not tracked before the session is focused";
    for (std::size_t f = 1; f < hands.size(); ++f) {
      EXPECT_FALSE(hands[f].fromControllers);
      ASSERT_TRUE(hands[f].joints[0].has_value()) << f;
      lost += hands[f].joints[1].has_value() ? 0 : 1;
      // the runtime plays the recording from the session's begin: frame f is displayed at (f + 1) periods
      const input::JointFrame rec = track.sample((double(f) + 1.0) / 90.0);
      EXPECT_LT((hands[f].joints[0]->joint[15].position - rec.hands[0].joint[15].position).norm(), 1e-5) << f;
    }
    EXPECT_NEAR(lost, 18, 2) << "0.2 s of the right hand lost at 90 Hz";
    EXPECT_FALSE(hands[0].recentre);
  }
  // no hand tracking: the controllers' grip poses (on the recorded palms) and their buttons
  setenv("FP_XR_NO_HANDS", "1", 1);
  setenv("FP_XR_CONTROLLERS", "0,1", 1);  // squeeze: point
  setenv("FP_XR_PROFILE", "/interaction_profiles/oculus/touch_controller", 1);
  engine::XrProgram xr("fp_test_xr_program");
  xr.createSession(binding());
  std::vector<engine::XrHands> hands;
  int recreated = 0;
  run(xr, 10, recreated, &hands);
  ASSERT_EQ(hands.size(), 10u);
  for (std::size_t f = 1; f < hands.size(); ++f) {
    const engine::XrHands& h = hands[f];
    EXPECT_TRUE(h.fromControllers);
    ASSERT_TRUE(h.joints[0] && h.joints[1]);
    // the palm where the recorded palm is; the index finger straight (pointing), the middle finger curled
    const input::JointFrame rec = track.sample(0.0);
    EXPECT_LT((h.joints[1]->joint[0].position - rec.hands[1].joint[0].position).norm(), 0.05);
  }
}

}  // namespace
}  // namespace fp
