// `fluidplaying --xr` against the test runtime (label xr, under Xvfb), with the core validation layer on: the
// fallback line without a runtime and --xr-required's exit code; a session that survives LOSS_PENDING, is
// ended by the runtime, submits every frame it waited for and draws two different eyes; recorded hands (and
// the controllers where there is no hand tracking) push the water and a headless replay of the recording
// gives the same state bit for bit; the eyes' disparity; frames paced by the display while the solver lags.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "engine/cli.h"
#include "engine/headless_runner.h"
#include "input/joint_track.h"
#include "sim/signed_distance.h"
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

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
}

const std::string kSource = FP_SOURCE_DIR;
const std::string kHandTank = " --scene " + kSource + "/assets/scenes/hand_tank_coarse.json";

/// the runtime as the app tests use it: virtual time unless told, the head low enough that the tank on its
/// table is in view, the recording's frame (the hand tank's) on the table; returns the validation file
std::string useRuntime(const std::string& dir, bool virtualTime = true) {
  const std::string validation = test::useTestRuntime(dir);
  setenv("FP_XR_STATS", (dir + "/stats.txt").c_str(), 1);
  std::filesystem::remove(dir + "/stats.txt");
  if (virtualTime)
    setenv("FP_XR_VIRTUAL_TIME", "1", 1);
  setenv("FP_XR_HEAD", "0,1.1,0,0", 1);
  setenv("FP_XR_HANDS_OFFSET", "0,0.75,-0.5", 1);
  setenv("FP_XR_SIZE", "96,80", 1);
  return validation;
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
  const AppRun run = runApp("--xr --no-window --scene " FP_SOURCE_DIR "/assets/scenes/hand_tank_coarse.json");
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

// The headset run records the hands it tracks (--record-hands) at its frames' simulated times; the headless
// replay of that file in fixed steps on one thread gives the same fluid, bit for bit. The hands are sized
// from the first tracked frame, in the replay as in the headset: with --hand-size 2 (where the hands rest
// before they are seen) the model hand's colliders would be twice the recorded hands' and the runs would
// differ. And the recorded push moves the water along +x.
TEST(XrApp, RecordedHandsPushTheWaterAndAHeadlessReplayIsBitIdentical) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Replay");
  const std::string validation = useRuntime(dir);
  setenv("FP_XR_HANDS", (kSource + "/assets/hands/two_hands_push.csv").c_str(), 1);
  const std::string recording = dir + "/hands.csv", xrStats = dir + "/xr.json",
                    replayStats = dir + "/replay.json";
  for (const std::string& f : {recording, xrStats, replayStats})
    std::filesystem::remove(f);
  // 42 frames: the push is under way (0.68 s); uniform resolution starts the water at rest (uniform-low: 288
  // particles, seconds)
  const std::string common = kHandTank + " --mode uniform-low --threads 1 --hand-size 2 --quiet";
  const AppRun live = runApp("--xr --no-window --fixed-step --frames 42 --record-hands " + recording +
                             " --stats " + xrStats + common);
  ASSERT_EQ(live.code, 0) << live.output;
  EXPECT_EQ(test::validationMessages(validation), "");
  EXPECT_EQ(test::runtimeStat(dir + "/stats.txt", "submitted"), 42);
  // frame 0 is not tracked yet, frame 1 sizes the hands and starts the water over at t = 0: 41 frames
  const input::JointTrack track = input::JointTrack::load(recording);
  ASSERT_EQ(track.frames().size(), 41u);
  EXPECT_TRUE(track.frames().front().hands[0].valid && track.frames().front().hands[1].valid);
  const AppRun replay =
      runApp("--headless --frames 41 --hand-script " + recording + " --stats " + replayStats + common);
  ASSERT_EQ(replay.code, 0) << replay.output;
  const nlohmann::json a = readJson(xrStats), b = readJson(replayStats);
  ASSERT_TRUE(a.is_object() && b.is_object());
  for (const char* key : {"steps", "sim_seconds", "particles_final", "mass_final", "momentum_final",
                          "density_error_mean", "density_error_max", "density_iterations_mean"})
    EXPECT_EQ(a.at(key).dump(), b.at(key).dump()) << key;
  // the push: 0.52 kg m/s along +x measured, against 0.14 up and -0.18 sideways (0.60, 0.04, -0.12 while the
  // divergence solve skipped particles with fewer than 20 neighbours: in these 288 coarse particles the
  // volume criterion now also corrects the surface layers the hands lift, so more of the push goes up and
  // sideways)
  const nlohmann::json& p = a.at("momentum_final");
  EXPECT_GT(double(p[0]), 0.3) << p.dump();
  EXPECT_GT(double(p[0]), 2.0 * std::abs(double(p[1]))) << p.dump();
  EXPECT_GT(double(p[0]), 2.0 * std::abs(double(p[2]))) << p.dump();
}

// Without hand tracking the controllers drive the same hands: their grip poses follow the recording's palms
// (the test runtime's controllers), so the same push moves the water.
TEST(XrApp, ControllersPushTheWaterWithoutHandTracking) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Controllers");
  const std::string validation = useRuntime(dir);
  setenv("FP_XR_NO_HANDS", "1", 1);
  setenv("FP_XR_HANDS", (kSource + "/assets/hands/two_hands_push.csv").c_str(), 1);
  const std::string recording = dir + "/hands.csv", stats = dir + "/xr.json";
  std::filesystem::remove(recording);
  const AppRun run = runApp("--xr --no-window --fixed-step --frames 42 --record-hands " + recording +
                            " --stats " + stats + kHandTank + " --mode uniform-low --threads 1 --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_EQ(test::validationMessages(validation), "");
  // the controllers' hands, on the recorded palms
  const input::JointTrack pushed = input::JointTrack::load(kSource + "/assets/hands/two_hands_push.csv");
  const input::JointTrack track = input::JointTrack::load(recording);
  ASSERT_GT(track.frames().size(), 30u);
  const input::JointFrame& last = track.frames().back();
  ASSERT_TRUE(last.hands[0].valid && last.hands[1].valid);
  for (int h = 0; h < 2; ++h) {
    // the runtime plays the recording in display time: frame 41 is displayed at 42 periods
    const input::JointFrame rec = pushed.sample(42.0 / 90.0);
    EXPECT_LT((last.hands[h].joint[0].position - rec.hands[h].joint[0].position).norm(), 0.05) << h;
  }
  const nlohmann::json p = readJson(stats).at("momentum_final");
  // 0.50 kg m/s along +x measured, against 0.08 and -0.09 sideways
  EXPECT_GT(double(p[0]), 0.25) << p.dump();
  EXPECT_GT(double(p[0]), 3.0 * std::abs(double(p[1]))) << p.dump();
  EXPECT_GT(double(p[0]), 3.0 * std::abs(double(p[2]))) << p.dump();
}

// The two eyes of one frame: both show water, and the hands (a feature at a known depth) appear shifted
// between them as the eyes' offset and their asymmetric fields of view predict. Head at (0, 1.1, 0) looking
// along -z; the tank 0.5 m ahead; the hands resting over its centre at z = -0.5 -+ 0.09 (left nearer).
TEST(XrApp, TheEyesDifferByTheirOffsetAndBothShowWater) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Eyes");
  const std::string validation = useRuntime(dir);
  const int size = 160;
  setenv("FP_XR_SIZE", "160,160", 1);
  setenv("FP_XR_CAPTURE", ("3," + dir).c_str(), 1);
  std::filesystem::remove(dir + "/eye0.ppm");
  const AppRun run =
      runApp("--xr --no-window --fixed-step --frames 4 --mode uniform-high --quiet" + kHandTank);
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_EQ(test::validationMessages(validation), "");
  struct Mask {
    double skinColumn = 0, waterColumn = 0;
    std::size_t skin = 0, water = 0;
  };
  std::array<Mask, 2> eye;
  for (int e = 0; e < 2; ++e) {
    int w = 0, h = 0;
    const auto px = readPpm(dir + "/eye" + std::to_string(e) + ".ppm", w, h);
    ASSERT_EQ(w, size);
    ASSERT_EQ(h, size);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int r = px[3 * (y * w + x)], g = px[3 * (y * w + x) + 1], b = px[3 * (y * w + x) + 2];
        if (r > b + 40 && r > g + 20) {  // skin
          eye[e].skinColumn += x;
          ++eye[e].skin;
        }
        if (y > h / 2 && b > r + 40 && g > r + 30) {  // water below the horizon (the sky is above it)
          eye[e].waterColumn += x;
          ++eye[e].water;
        }
      }
    }
    ASSERT_GT(eye[e].skin, 40u) << "eye " << e << " shows no hand";
    EXPECT_GT(eye[e].water, std::size_t(size * size / 20)) << "eye " << e << " shows little water";
    eye[e].skinColumn /= double(eye[e].skin);
    eye[e].waterColumn /= double(eye[e].water);
  }
  // a point straight ahead at depth d is at column (x / d - tan(left)) / (tan(right) - tan(left)) * width;
  // the left eye (fov -0.95 .. 0.80 rad) sees it ipd/2 to its right, the right eye (-0.80 .. 0.95) to its
  // left
  const double span = std::tan(0.95) + std::tan(0.80), ipd = 0.064;
  auto disparity = [&](double d) { return (ipd / d + std::tan(0.95) - std::tan(0.80)) / span * size; };
  const double measured = eye[0].skinColumn - eye[1].skinColumn;
  // the nearer hand (34.6 px at 0.41 m) covers most of the farther one (31.4 px at 0.59 m): 34.4 px measured
  EXPECT_GT(measured, disparity(0.59) - 0.5) << "near " << disparity(0.41);
  EXPECT_LT(measured, disparity(0.41) + 0.5) << "far " << disparity(0.59);
  // without the eye offset the shift would be the fields of view's asymmetry alone (24.3 px, infinitely far)
  EXPECT_GT(measured, disparity(1e9) + 5.0);
  // the water spans the tank's depth around 0.5 m
  const double water = eye[0].waterColumn - eye[1].waterColumn;
  EXPECT_GT(water, disparity(0.8));
  EXPECT_LT(water, disparity(0.3));
}

// The time scale of the real-time pacing tests: FP_TEST_TIME_SCALE=S stretches every period and delay S
// times; without it a machine loaded beyond 1.5 times its cores (a parallel build or soak beside the test, as
// in CI's ctest -j2) runs them four times slower instead of skipping them, and one loaded beyond six times
// its cores skips them (returns 0).
double realTimeScale() {
  if (const char* text = std::getenv("FP_TEST_TIME_SCALE"))
    return std::max(1.0, std::atof(text));
  double load = 0.0;
  std::ifstream("/proc/loadavg") >> load;
  const double cores = double(std::max(1u, std::thread::hardware_concurrency()));
  if (load > 6.0 * cores)
    return 0.0;
  return load > 1.5 * cores ? 4.0 : 1.0;
}

// Frame pacing in real time: with the solver made slower than the display (the test knob: dt_max = 0.5 ms,
// so a frame's 0.1 s of simulated time takes 200 steps, far more than the 60% of a period the frame gives
// them; one thread for the solver, the other core for llvmpipe), after six frames (shaders compiled, late)
// every display period gets exactly one frame, submitted before its display time, counted by the runtime's
// frame log; the water slows instead. A real-time test: see realTimeScale() for a loaded machine.
TEST(XrApp, EveryPeriodGetsOneFrameWhileTheSolverLags) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const double scale = realTimeScale();
  if (scale <= 0.0)
    GTEST_SKIP() << "a real-time test: the machine is loaded beyond six times its cores";
  const std::string dir = dirOf("Pacing");
  const std::string validation = useRuntime(dir, false);
  const long period = long(400000000 * scale);  // 2.5 Hz: room for two llvmpipe eyes on a loaded machine
  setenv("FP_XR_PERIOD_NS", std::to_string(period).c_str(), 1);
  const std::string log = dir + "/frames.txt";
  std::filesystem::remove(log);
  setenv("FP_XR_FRAME_LOG", log.c_str(), 1);
  const int frames = 13;
  const AppRun run = runApp("--xr --no-window --frames " + std::to_string(frames) +
                            " --mode uniform-low --set dt_max=0.0005 --threads 1" + kHandTank);
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_EQ(test::validationMessages(validation), "");
  std::ifstream in(log);
  std::vector<std::pair<long long, long long>> ends;  // display time, xrEndFrame time [ns]
  long long display = 0, end = 0;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    if (fields >> display >> end)
      ends.emplace_back(display, end);
  }
  ASSERT_EQ(int(ends.size()), frames);
  for (std::size_t i = 6; i < ends.size(); ++i) {
    EXPECT_EQ(ends[i].first - ends[i - 1].first, period)
        << "frame " << i << ": a display period without a frame";
    EXPECT_LT(ends[i].second, ends[i].first) << "frame " << i << " submitted after its display time";
  }
  // the simulation fell behind: less simulated time than displayed
  const std::size_t at = run.output.find("simulated ");
  ASSERT_NE(at, std::string::npos) << run.output;
  const double simulated = std::atof(run.output.c_str() + at + 10);
  EXPECT_LT(simulated, 0.5 * frames * period * 1e-9) << run.output;
}

/// the runtime's frame log: display time, xrEndFrame time [ns] and (FP_XR_FRAME_HASH) the left eye's hash
struct LoggedFrame {
  long long display = 0, end = 0;
  unsigned long long hash = 0;
};
std::vector<LoggedFrame> readFrameLog(const std::string& path) {
  std::vector<LoggedFrame> frames;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    LoggedFrame f;
    long long skip = 0;
    if (!(fields >> f.display >> f.end))
      continue;
    for (int k = 0; k < 6; ++k)
      fields >> skip;  // xrWaitFrame called and returned, the eyes acquired and released
    fields >> f.hash;
    frames.push_back(f);
  }
  return frames;
}

/// the number after `key` in the app's last line ("frames 32, submitted 32, states taken 12, ...")
double outputNumber(const std::string& output, const std::string& key) {
  const std::size_t at = output.rfind(key);
  return at == std::string::npos ? -1.0 : std::atof(output.c_str() + at + key.size());
}

// A solver step longer than two display periods (the test knob --debug-slow-steps 5,400: the first 5 steps
// each take 400 ms more, at a 150 ms display period; uniform-low, one solver thread) never makes a frame
// late: after three warm-up frames every display period gets one frame, submitted before its display time; a
// frame whose steps still run draws the last completed state again (the left eye's image is the one before
// it, the head being still: the runtime hashes each submitted image), so the images change at most once per
// state the app took; and once the slow steps are done the simulation runs at the display's pace again.
// Before the fix (the frame waited for its steps) each slow step made the frame after it late by about two
// periods.
TEST(XrApp, ASolverStepLongerThanTwoPeriodsNeverMakesAFrameLate) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const double scale = realTimeScale();
  if (scale <= 0.0)
    GTEST_SKIP() << "a real-time test: the machine is loaded beyond six times its cores";
  const std::string dir = dirOf("SlowStep");
  const std::string validation = useRuntime(dir, false);
  const double periodSeconds = 0.15 * scale, slowMs = 400.0 * scale;
  const long long period = (long long)(periodSeconds * 1e9);
  setenv("FP_XR_PERIOD_NS", std::to_string(period).c_str(), 1);
  setenv("FP_XR_HANDS", (kSource + "/assets/hands/two_hands_push.csv").c_str(), 1);
  const std::string log = dir + "/frames.txt";
  std::filesystem::remove(log);
  setenv("FP_XR_FRAME_LOG", log.c_str(), 1);
  setenv("FP_XR_FRAME_HASH", "1", 1);
  const int frames = 32, warmUp = 3, slowSteps = 5;
  std::ostringstream args;
  args << "--xr --no-window --frames " << frames << " --mode uniform-low --threads 1 --debug-slow-steps "
       << slowSteps << "," << slowMs << kHandTank;
  const AppRun run = runApp(args.str());
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_EQ(test::validationMessages(validation), "");
  const std::vector<LoggedFrame> log_ = readFrameLog(log);
  ASSERT_EQ(int(log_.size()), frames);
  int late = 0, repeated = 0, changed = 0;
  for (std::size_t i = warmUp; i < log_.size(); ++i) {
    const bool missed = log_[i].display - log_[i - 1].display != period;
    const bool lateEnd = log_[i].end >= log_[i].display;
    late += missed || lateEnd;
    EXPECT_FALSE(missed) << "frame " << i << ": a display period without a frame";
    EXPECT_FALSE(lateEnd) << "frame " << i << " submitted " << 1e-6 * double(log_[i].end - log_[i].display)
                          << " ms after its display time";
  }
  EXPECT_EQ(late, 0);
  for (std::size_t i = 2; i < log_.size(); ++i) {  // frame 0 is not visible yet (no image)
    ASSERT_NE(log_[i].hash, 0u) << "frame " << i << " has no image";
    (log_[i].hash == log_[i - 1].hash ? repeated : changed) += 1;
  }
  // each slow step spans two frames or more that show the state before it again (the first one's start
  // overlaps the warm-up), and an image changes only in a frame that took a new state
  const double taken = outputNumber(run.output, "states taken ");
  EXPECT_GE(repeated, 2 * (slowSteps - 1)) << run.output;
  EXPECT_LE(changed, taken) << "an image changed in a frame that took no new state";
  // caught up: the last frames each show a new state again, and simulate about their display time (at most
  // 0.1 s a frame: AppSession drops a longer stall)
  for (std::size_t i = log_.size() - 8; i < log_.size(); ++i)
    EXPECT_NE(log_[i].hash, log_[i - 1].hash) << "frame " << i << " still shows the state before it";
  EXPECT_GT(outputNumber(run.output, "simulated "), 0.4 * std::min(periodSeconds, 0.1) * 8) << run.output;
}

// Tracking lost mid-push (two_hands_lost.csv: the right hand from 0.7 s to 0.9 s, under water), replayed by
// the tracked hands as the headset drives them (engine/tracked_hands, the same code): at every frame no fluid
// particle is inside a hand collider, and no collider moved farther than its hand's joints did in the frame
// plus the easing distance (1 m/s x the frame); the lost hand rose out of the water and came back.
TEST(XrHands, TrackingLostMidPushNeverJumpsThroughTheWater) {
  const std::string recording = kSource + "/assets/hands/two_hands_lost.csv";
  const input::JointTrack track = input::JointTrack::load(recording);
  engine::CliOptions o;
  o.headless = true;
  o.quiet = true;
  o.scenePath = kSource + "/assets/scenes/hand_tank_coarse.json";
  o.handScript = recording;
  o.frames = 66;  // 1.1 s
  const double frameDt = 1.0 / 60.0, easeSpeed = 1.0;
  std::vector<double> times;
  std::vector<sim::Vec3d> previous;  // the hand colliders' positions at the last frame
  std::size_t inside = 0;
  double worstExcess = -1.0;  // largest move beyond the bound [m]
  double rightPalmLow = 1e9, rightPalmHigh = -1e9;
  auto jointMove = [&](double t0, double t1, int hand) {
    const input::JointFrame a = track.sample(t0), b = track.sample(t1);
    if (!a.hands[hand].valid || !b.hands[hand].valid)
      return 0.0;
    double m = 0.0;
    for (int j = 0; j < input::kHandJoints; ++j)
      m = std::max(m, (a.hands[hand].joint[j].position - b.hands[hand].joint[j].position).norm());
    return m;
  };
  std::ostringstream out, progress;
  const engine::RunSummary summary = engine::runHeadless(
      o, out, progress, [&](int, const sim::Simulation& simulation, const sim::SplashParticles&) {
        std::vector<std::size_t> hand;  // hand colliders, left then right
        std::vector<int> side;
        for (std::size_t c = 0; c < simulation.colliders().size(); ++c) {
          const std::string& name = simulation.colliders()[c].desc.name;
          if (name.rfind("left_", 0) == 0 || name.rfind("right_", 0) == 0) {
            hand.push_back(c);
            side.push_back(name[0] == 'l' ? 0 : 1);
          }
        }
        ASSERT_EQ(hand.size(), 32u);
        const sim::ParticleSet& p = simulation.particles();
        for (std::size_t c : hand) {
          const sim::ColliderState& cs = simulation.colliders()[c];
          for (std::size_t i = 0; i < p.size(); ++i) {
            const sim::Vec3d local = cs.orientation.conjugate() * (p.x[i].cast<double>() - cs.position);
            inside += sim::signedDistanceLocal(cs.desc, local) < 0.0;
          }
        }
        // the colliders now are where the hands were sent at the last frame's start (the frame before's)
        times.push_back(simulation.time());
        std::vector<sim::Vec3d> now;
        for (std::size_t c : hand)
          now.push_back(simulation.colliders()[c].position);
        const std::size_t k = times.size() - 1;
        if (k >= 2 && !previous.empty()) {
          for (std::size_t n = 0; n < hand.size(); ++n) {
            const double bound = jointMove(times[k - 2], times[k - 1], side[n]) + easeSpeed * frameDt;
            worstExcess = std::max(worstExcess, (now[n] - previous[n]).norm() - bound);
          }
        }
        const sim::Vec3d& palm = simulation.colliders()[hand[16]].position;  // right_palm
        if (times.back() > 0.5 && times.back() < 0.7)
          rightPalmLow = std::min(rightPalmLow, palm.y());
        if (times.back() > 0.7 && times.back() < 0.95)
          rightPalmHigh = std::max(rightPalmHigh, palm.y());
        previous = now;
      });
  ASSERT_EQ(summary.status, "ok") << summary.message;
  EXPECT_EQ(summary.frames, 66);
  EXPECT_EQ(inside, 0u) << "fluid particles inside a hand collider, summed over the frames";
  // the solver integrates a driven pose over its step, which may end a step short of or past the frame's
  // target: a lag of at most one step at the hand's speed (1 m/s x dt_max = 5 mm); 3.9 mm measured
  EXPECT_LE(worstExcess, easeSpeed * 0.005) << "a collider moved farther than its joints plus the easing";
  // lost under water, the right hand rose (its palm 5 cm or more), then came back
  EXPECT_GT(rightPalmHigh - rightPalmLow, 0.05);
}

// The same replay, in the seeds whose left fist, closing under water, trapped single particles among its
// finger and palm particles (docs/robustness.md, Water shut in a closing fist). Before session 32, on the
// coarse tank the factor's denominator collapsed there: seed 6 threw a particle at 34.8 m/s, seed 12 went
// unstable at 137 m/s. On the r = 5 mm tank (the desktop's default) such particles rattled between the fist's
// walls ever faster as their speed shrank the step: seeds 4 and 9 went unstable (above 50 m/s). With the
// floor on the denominator and caged particles moved with their cage, the fastest particle of every step
// stays under 5 m/s (the hands move at under 1 m/s; of seeds 1-80 of the coarse replay and 1-36 of the fine
// one, two runs went above 5 m/s, at 5.6 and 8.2).
TEST(XrHands, AFistClosingUnderWaterDoesNotThrowTheWater) {
  struct Case {
    const char* scene;
    std::uint64_t seed;
  };
  for (const Case& c : {Case{"hand_tank_coarse.json", 6}, Case{"hand_tank_coarse.json", 12},
                        Case{"hand_tank.json", 4}, Case{"hand_tank.json", 9}}) {
    engine::CliOptions o;
    o.headless = true;
    o.quiet = true;
    o.threads = 2;  // the trajectory is the 2-thread one whatever the machine
    o.seed = c.seed;
    o.scenePath = kSource + "/assets/scenes/" + c.scene;
    o.handScript = kSource + "/assets/hands/two_hands_lost.csv";
    o.frames = 66;
    std::ostringstream out, progress;
    double frameFastest = 0.0;
    const engine::RunSummary summary = engine::runHeadless(
        o, out, progress, [&](int, const sim::Simulation& simulation, const sim::SplashParticles&) {
          for (const sim::Vec3& v : simulation.particles().v)
            frameFastest = std::max(frameFastest, double(v.norm()));
        });
    const std::string what = std::string(c.scene) + " seed " + std::to_string(c.seed);
    ASSERT_EQ(summary.status, "ok") << what << ": " << summary.message;
    std::printf(
        "%s: fastest particle %.2f m/s at t = %.3f s (%.2f m/s in the frames), %llu particle-steps caged\n",
        what.c_str(), summary.maxSpeed, summary.maxSpeedTime, frameFastest,
        static_cast<unsigned long long>(summary.cagedParticleSteps));
    EXPECT_LT(summary.maxSpeed, 5.0) << what;
    // the run's figure covers every step, the frames among them
    EXPECT_GE(summary.maxSpeed, frameFastest) << what;
    EXPECT_GT(summary.maxSpeedTime, 0.0) << what;
    EXPECT_LE(summary.maxSpeedTime, summary.simSeconds) << what;
  }
}

}  // namespace
}  // namespace fp
