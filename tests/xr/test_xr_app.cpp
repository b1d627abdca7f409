// `fluidplaying --xr` against the test runtime (label xr, under Xvfb), with the core validation layer on: the
// fallback line without a runtime and --xr-required's exit code, and a session that survives LOSS_PENDING, is
// ended by the runtime, submits every frame it waited for and draws two different eyes.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/xr/xr_test_env.h"

namespace fp {
namespace {

struct AppRun {
  int code = -1;
  std::string output;
};

AppRun runApp(const std::string& args) {
  const std::string command = std::string(FP_FLUIDPLAYING_EXE) + " " + args + " 2>&1";
  AppRun r;
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 512> buffer{};
  while (pipe && fgets(buffer.data(), int(buffer.size()), pipe))
    r.output += buffer.data();
  const int status = pipe ? pclose(pipe) : -1;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string dirOf(const char* test) {
  return (std::filesystem::temp_directory_path() / "fp_xr_app_test" / test).string();
}

std::vector<unsigned char> readPpm(const std::string& path, int& w, int& h) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int max = 0;
  in >> magic >> w >> h >> max;
  in.get();
  std::vector<unsigned char> px(std::size_t(w) * h * 3);
  in.read(reinterpret_cast<char*>(px.data()), std::streamsize(px.size()));
  return in ? px : std::vector<unsigned char>{};
}

TEST(XrApp, NoRuntimeFallsBackInOneLineAndRequiredExits) {
  test::useTestRuntime(dirOf("NoRuntime"));
  setenv("XR_RUNTIME_JSON", "/nonexistent/openxr_runtime.json", 1);
  const std::string args =
      "--xr --headless --scene " FP_SOURCE_DIR "/assets/scenes/tiny_dam_break.json --frames 2 --quiet";
  const AppRun fallback = runApp(args);
  EXPECT_EQ(fallback.code, 0) << fallback.output;
  EXPECT_NE(fallback.output.find("fluidplaying: no OpenXR runtime"), std::string::npos) << fallback.output;
  EXPECT_NE(fallback.output.find("; playing on the desktop instead\n"), std::string::npos) << fallback.output;
  const AppRun required = runApp("--xr-required --headless --frames 2");
  EXPECT_EQ(required.code, 5) << required.output;
  EXPECT_NE(required.output.find("(--xr-required)"), std::string::npos) << required.output;
  // a runtime without GL support
  test::useTestRuntime(dirOf("NoGl"));
  setenv("FP_XR_NO_GL", "1", 1);
  const AppRun noGl = runApp("--xr-required");
  EXPECT_EQ(noGl.code, 5);
  EXPECT_NE(noGl.output.find("no OpenGL support"), std::string::npos) << noGl.output;
}

TEST(XrApp, SessionSurvivesLossPendingEndsWithTheRuntimeAndDrawsBothEyes) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Session");
  const std::string validation = test::useTestRuntime(dir);
  const std::string stats = dir + "/stats.txt";
  std::filesystem::remove(stats);
  std::filesystem::remove(dir + "/eye0.ppm");
  setenv("FP_XR_STATS", stats.c_str(), 1);
  setenv("FP_XR_VIRTUAL_TIME", "1", 1);
  setenv("FP_XR_HEAD", "0,1.1,0,0", 1);  // low enough that the tank on its table is in view
  setenv("FP_XR_SIZE", "96,80", 1);
  setenv("FP_XR_HANDS", FP_SOURCE_DIR "/assets/hands/two_hands_push.csv", 1);
  setenv("FP_XR_HANDS_OFFSET", "0,0.75,-0.5", 1);
  setenv("FP_XR_EVENTS", "8:loss_pending,24:exit", 1);
  setenv("FP_XR_CAPTURE", ("20," + dir).c_str(), 1);
  const AppRun run = runApp("--xr --no-window --scene " FP_SOURCE_DIR "/assets/scenes/hand_tank.json");
  EXPECT_EQ(run.code, 0) << run.output;
  EXPECT_NE(run.output.find("sessions recreated 1"), std::string::npos) << run.output;
  EXPECT_EQ(test::runtimeStat(stats, "sessions"), 2);
  EXPECT_EQ(test::runtimeStat(stats, "submitted"), test::runtimeStat(stats, "waited"));
  EXPECT_EQ(test::runtimeStat(stats, "ended"), 1);
  EXPECT_EQ(test::validationMessages(validation), "");
  int w0 = 0, h0 = 0, w1 = 0, h1 = 0;
  const auto eye0 = readPpm(dir + "/eye0.ppm", w0, h0);
  const auto eye1 = readPpm(dir + "/eye1.ppm", w1, h1);
  ASSERT_FALSE(eye0.empty());
  ASSERT_EQ(eye0.size(), eye1.size());
  EXPECT_EQ(w0, 96);
  EXPECT_EQ(h0, 80);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < eye0.size(); ++i)
    differ += eye0[i] != eye1[i];
  EXPECT_GT(differ, eye0.size() / 50) << "the eyes see from 6.4 cm apart";
}

}  // namespace
}  // namespace fp
