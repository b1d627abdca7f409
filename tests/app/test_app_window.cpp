// The desktop app in a real window (label gl; run under Xvfb, e.g. xvfb-run -a ctest -L gl): the app starts,
// a recorded hand pushes into the tank and the water gains momentum in the push direction, the panel is
// drawn, and the screenshot is written with the panel on it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/desktop_platform.h"
#include "engine/headless_app.h"
#include "render/image.h"

using namespace fp;
using namespace fp::engine;

namespace {

bool haveDisplay() {
  const char* d = std::getenv("DISPLAY");
  return d && *d;
}

/// A platform that records the fluid's momentum after every frame's steps, around the desktop window.
class Probe : public AppPlatform {
 public:
  explicit Probe(DesktopPlatform& window) : m_window(window) {}
  bool running() override { return m_window.running(); }
  FrameClock beginFrame() override { return m_window.beginFrame(); }
  void input(AppSession& session, const FrameClock& clock) override {
    const sim::Vec3d p = session.simulation().totalMomentum();
    maxAlong = std::max(maxAlong, p.x());
    maxSideways = std::max(maxSideways, std::abs(p.z()));
    handX = session.handPose().position.x();
    m_window.input(session, clock);
  }
  void capture(AppSession& session, int frame) override { m_window.capture(session, frame); }
  void draw(AppSession& session, int frame) override {
    m_window.draw(session, frame);
    uiVertices = std::max(uiVertices, m_window.uiVertexCount());
  }
  double stepBudget() const override { return m_window.stepBudget(); }
  double maxAlong = 0.0;     ///< largest fluid momentum along +x, the push [kg m/s]
  double maxSideways = 0.0;  ///< largest |fluid momentum| along z [kg m/s]
  double handX = 0.0;
  int uiVertices = 0;

 private:
  DesktopPlatform& m_window;
};

}  // namespace

TEST(AppWindowTest, RecordedHandPushesTheWaterPanelDrawnScreenshotWritten) {
  if (!haveDisplay())
    GTEST_SKIP() << "no DISPLAY: window tests run under Xvfb (scripts/bootstrap.sh test does)";
  const std::string shot = (std::filesystem::path(::testing::TempDir()) / "fp_app_window.png").string();
  std::filesystem::remove(shot);
  const std::string src = FP_SOURCE_DIR;
  // push.csv dips the flat hand in by 0.4 s and pushes along +x at 0.45 m/s from 0.4 s; 40 frames of 1/60 s
  // reach 0.67 s. Uniform-high starts the water at rest, so all of its momentum comes from the hand (in the
  // closed tank the far wall later pushes it back: the test looks at the largest momentum during the push).
  const CliOptions o =
      parseCommandLine({"--scene", src + "/assets/scenes/hand_tank_coarse.json", "--mode", "uniform-high",
                        "--hand-script", src + "/assets/hands/push.csv", "--fixed-step", "--frames", "40",
                        "--width", "480", "--height", "320", "--screenshot", shot});
  DesktopPlatform window(o, o.frames);
  AppSession session(sessionConfigOf(o));
  Probe probe(window);
  EXPECT_EQ(runAppLoop(session, probe, o.frames), 40);
  window.finish();
  ASSERT_TRUE(session.error().empty()) << session.error();
  EXPECT_NEAR(session.simulation().time(), 40.0 / 60.0, 0.01);  // fixed steps: one frame, 1/60 s
  EXPECT_GT(probe.handX, -0.05);                                // the replay moved the hand along +x
  // the water gained momentum along the push (0.3 kg m/s measured), far more than sideways
  EXPECT_GT(probe.maxAlong, 0.15) << "sideways " << probe.maxSideways;
  EXPECT_GT(probe.maxAlong, 4.0 * probe.maxSideways);
  // the panel was drawn and is in the screenshot: dark ImGui pixels where it sits, the bright scene beside it
  EXPECT_GT(probe.uiVertices, 1000);  // 1,800 measured at 480 x 320
  ASSERT_TRUE(std::filesystem::exists(shot));
  const render::Image image = render::readPng(shot);
  ASSERT_EQ(image.width, 480);
  ASSERT_EQ(image.height, 320);
  auto darkShare = [&](int x0, int y0, int x1, int y1) {
    int dark = 0, all = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const std::uint8_t* c = image.at(x, y);
        dark += c[0] < 70 && c[1] < 70 && c[2] < 90;
        ++all;
      }
    }
    return double(dark) / all;
  };
  EXPECT_GT(darkShare(20, 40, 200, 300), 0.4);  // the panel's dark background
  EXPECT_LT(darkShare(456, 0, 480, 320), 0.2);  // sky, floor and water right of it
}

TEST(AppWindowTest, ExecutableWritesScreenshotOfItsLastFrame) {
  if (!haveDisplay())
    GTEST_SKIP() << "no DISPLAY: window tests run under Xvfb (scripts/bootstrap.sh test does)";
  const std::string shot = (std::filesystem::path(::testing::TempDir()) / "fp_app_exe.png").string();
  std::filesystem::remove(shot);
  const std::string cmd = std::string(FP_FLUIDPLAYING_EXE) + " --quiet --frames 3 --width 320 --height 200 " +
                          "--scene " + FP_SOURCE_DIR + "/assets/scenes/tiny_dam_break.json --screenshot " +
                          shot;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const render::Image image = render::readPng(shot);
  EXPECT_EQ(image.width, 320);
  EXPECT_EQ(image.height, 200);
}

// The window's default scene is the hand tank at r = 5 mm; where the window draws with software OpenGL
// (llvmpipe under Xvfb) the rasteriser shares the simulation's cores, and the window loads the coarse tank
// instead, saying so in one line. A scene given on the command line is always the one loaded.
TEST(AppWindowTest, DefaultSceneIsTheFineHandTankExceptOnSoftwareGl) {
  if (!haveDisplay())
    GTEST_SKIP() << "no DISPLAY: window tests run under Xvfb (scripts/bootstrap.sh test does)";
  const std::string out = (std::filesystem::path(::testing::TempDir()) / "fp_app_default.txt").string();
  auto run = [&out](const std::string& args) {
    const std::string cmd = std::string(FP_FLUIDPLAYING_EXE) +
                            " --frames 2 --width 160 --height 120 --no-panel " + args + " > " + out;
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream in(out);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const std::string defaulted = run("");
  const std::size_t window = defaulted.find("window ");
  ASSERT_NE(window, std::string::npos) << defaulted;
  const std::string context = defaulted.substr(window, defaulted.find(';', window) - window);
  const bool software = isSoftwareGl(context);
  if (context.find("llvmpipe") != std::string::npos) {  // Xvfb's Mesa, as in CI
    EXPECT_TRUE(software) << context;
  }
  EXPECT_EQ(defaulted.find("software OpenGL: the coarse hand tank") != std::string::npos, software)
      << defaulted;
  EXPECT_NE(defaulted.find(software ? "; scene hand tank coarse (fluidplaying)"
                                    : "; scene hand tank (fluidplaying)"),
            std::string::npos)
      << defaulted;
  const std::string given = run("--scene " FP_SOURCE_DIR "/assets/scenes/hand_tank.json");
  EXPECT_EQ(given.find("software OpenGL"), std::string::npos) << given;
  EXPECT_NE(given.find("; scene hand tank (fluidplaying)"), std::string::npos) << given;
  // a saved state belongs to the default scene it was saved from: never switched (the coarse tank refuses it)
  const std::string state = (std::filesystem::path(::testing::TempDir()) / "fp_app_default.state").string();
  std::filesystem::remove(state);
  run("--scene " FP_SOURCE_DIR "/assets/scenes/hand_tank.json --save-state " + state);
  ASSERT_TRUE(std::filesystem::exists(state)) << state;
  const std::string loaded = run("--load-state " + state);
  EXPECT_EQ(loaded.find("software OpenGL"), std::string::npos) << loaded;
  EXPECT_NE(loaded.find("; scene hand tank (fluidplaying)"), std::string::npos) << loaded;
}
