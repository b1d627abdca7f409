// Bad input of every class docs/robustness.md lists that no other suite covers: unreadable and empty files of
// every format, presets that are not JSON or carry wrong types, non-finite numbers and truncations of a hand
// recording, an open mesh, and a full disk for frames, stats and saved states. Every error is one line.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "engine/app_session.h"
#include "engine/cli.h"
#include "engine/presets.h"
#include "engine/scene_loader.h"
#include "input/pose_track.h"
#include "sim/mesh.h"
#include "sim/simulation.h"
#include "sim/state_io.h"

namespace {

using namespace fp;
namespace fs = std::filesystem;

/// a fresh scratch folder for one test
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("fp_robustness_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// `load` throws an InputError whose message is one line and contains `expected`
void expectOneLineError(const std::function<void()>& load, const std::string& expected) {
  try {
    load();
    ADD_FAILURE() << "no error (expected one containing '" << expected << "')";
  } catch (const sim::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find(expected), std::string::npos) << what;
  }
}

const engine::Preset kBase{};

TEST(RobustnessTest, UnreadableFilesOfEveryFormat) {
  // a folder where a file is expected: unreadable whoever runs the test (root reads any file)
  const fs::path dir = scratch("unreadable");
  const std::string path = dir.string();
  expectOneLineError([&] { engine::loadScene(path); }, path);
  expectOneLineError([&] { engine::loadPreset(path, kBase); }, path);
  expectOneLineError([&] { input::PoseTrack::load(path); }, path);
  expectOneLineError([&] { sim::TriangleMesh::loadObj(path); }, path);
  sim::SceneDesc scene = engine::loadScene(engine::assetPath("assets/scenes/tiny_dam_break.json"));
  sim::Simulation simulation(scene);
  expectOneLineError([&] { sim::loadState(path, simulation); }, path);
}

TEST(RobustnessTest, EmptyFilesOfEveryFormat) {
  const fs::path dir = scratch("empty");
  const std::string path = (dir / "empty").string();
  writeFile(path, "");
  expectOneLineError([&] { engine::loadScene(path); }, path);
  expectOneLineError([&] { engine::loadPreset(path, kBase); }, path);
  expectOneLineError([&] { input::PoseTrack::load(path); }, path);
  expectOneLineError([&] { sim::TriangleMesh::loadObj(path); }, path);
}

TEST(RobustnessTest, PresetThatIsNotJsonOrHasWrongTypesRangesKeys) {
  const fs::path dir = scratch("preset");
  const std::string path = (dir / "preset.json").string();
  const std::pair<const char*, const char*> cases[] = {
      {"{\"mode\": \"fluidplaying\",", "invalid JSON"},
      {"[1, 2, 3]", "object"},
      {"{\"parameters\": {\"viscosity\": \"high\"}}", "viscosity"},
      {"{\"parameters\": {\"gravity\": [0, -9.81]}}", "gravity"},
      {"{\"parameters\": {\"viscosity\": 7}}", "viscosity"},
      {"{\"parameters\": {\"viscosity\": 1e999}}", "preset.json"},
      {"{\"parameters\": {\"viscosityy\": 0.1}}", "unknown parameter"},
      {"{\"colour\": \"blue\"}", "unknown key"},
      {"{\"mode\": \"adaptive\"}", "mode"},
      {"{\"parameters\": {\"vorticity_lo\": 20}}", "vorticity_lo"},
  };
  for (const auto& [text, expected] : cases) {
    SCOPED_TRACE(text);
    writeFile(path, text);
    expectOneLineError([&] { engine::loadPreset(path, kBase); }, expected);
  }
}

TEST(RobustnessTest, RecordingWithNonFiniteOrHugeNumbers) {
  const fs::path dir = scratch("recording");
  const std::string path = (dir / "hand.csv").string();
  for (const char* value : {"nan", "inf", "-inf", "1e999", "0x1p99999", "1e308*10", ""}) {
    SCOPED_TRACE(value);
    writeFile(path, std::string("time,px,py,pz,qw,qx,qy,qz,grip\n0,0,0.3,0,1,0,0,0,0\n0.5,") + value +
                        ",0.3,0,1,0,0,0,0\n");
    expectOneLineError([&] { input::PoseTrack::load(path); }, "hand.csv");
  }
}

TEST(RobustnessTest, TruncatedRecordingLoadsItsWholeLinesOrNamesTheLine) {
  // every truncation of a shipped recording: either the keys of the complete lines (a cut inside a number
  // may still be a number: the last key then differs) or an error naming the file
  const std::string source = engine::assetPath("assets/hands/splash.csv");
  std::ifstream in(source, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(text.size(), 100u);
  const input::PoseTrack full = input::PoseTrack::load(source);
  const fs::path dir = scratch("truncated");
  const std::string path = (dir / "cut.csv").string();
  int loaded = 0, refused = 0;
  for (std::size_t len = 0; len < text.size(); ++len) {
    writeFile(path, text.substr(0, len));
    try {
      const input::PoseTrack cut = input::PoseTrack::load(path);
      EXPECT_LE(cut.keys().size(), full.keys().size());
      ++loaded;
    } catch (const sim::InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_NE(what.find("cut.csv"), std::string::npos) << what;
      ++refused;
    }
  }
  EXPECT_GT(loaded, 0);
  EXPECT_GT(refused, 0);
}

TEST(RobustnessTest, OpenAndEmptyMeshes) {
  const fs::path dir = scratch("mesh");
  // a cube with its top face missing: not closed
  const std::string open = (dir / "open.obj").string();
  writeFile(open,
            "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
            "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 3 4 8 7\nf 2 3 7 6\n");
  const std::string empty = (dir / "empty.obj").string();
  writeFile(empty, "# no faces\nv 0 0 0\n");
  expectOneLineError([&] { sim::TriangleMesh::loadObj(empty); }, "empty.obj");
  const std::string scene = (dir / "scene.json").string();
  writeFile(scene, R"({
    "domain": {"min": [-0.3, -0.1, -0.2], "max": [0.3, 0.4, 0.2]},
    "parameters": {"particle_radius": 0.02},
    "fluid": [{"min": [-0.2, 0.0, -0.1], "max": [0.2, 0.1, 0.1]}],
    "colliders": [
      {"name": "tank", "shape": "box", "container": true, "half_extents": [0.2, 0.15, 0.1],
       "position": [0.0, 0.15, 0.0]},
      {"name": "cup", "shape": "mesh", "file": "open.obj", "scale": 0.05, "position": [0.0, 0.2, 0.0]}
    ]})");
  // an open mesh is refused with a one-line error, or simulated as its surface; never a crash
  try {
    sim::Simulation simulation(engine::loadScene(scene));
    for (int k = 0; k < 5; ++k)
      simulation.step();
  } catch (const sim::InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

/// exit status of `ENV fluidplaying ARGS`, its error output in `err`
int runExe(const std::string& args, std::string& err, const std::string& env = "") {
  // one log per test: ctest runs the tests in parallel
  const fs::path log =
      fs::temp_directory_path() / (std::string("fp_robustness_") +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".txt");
  const std::string cmd =
      env + " " + std::string(FP_FLUIDPLAYING_EXE) + " " + args + " > /dev/null 2> " + log.string();
  const int status = std::system(cmd.c_str());
  std::ifstream in(log);
  err.assign((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RobustnessTest, FullDiskForFramesStatsAndStates) {
  if (!fs::exists("/dev/full"))
    GTEST_SKIP() << "no /dev/full";
  const fs::path dir = scratch("full");
  // the first frame's file is /dev/full: every write to it fails with "no space left on device"
  fs::create_symlink("/dev/full", dir / "frame_00000.png");
  const std::string scene = engine::assetPath("assets/scenes/tiny_dam_break.json");
  std::string err;
  // OSMesa keeps a few of its own allocations when the program exits early with an error; under the sanitizer
  // build LeakSanitizer would report them (they are Mesa's, not ours), so leak checking is off for this run
  // only
  EXPECT_EQ(runExe("--headless --render --quiet --frames 2 --width 64 --height 48 --scene " + scene +
                       " --out " + dir.string(),
                   err, "ASAN_OPTIONS=detect_leaks=0"),
            engine::kExitInput);
  EXPECT_NE(err.find("frame_00000.png"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(runExe("--headless --quiet --frames 2 --scene " + scene + " --stats /dev/full", err),
            engine::kExitInput);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  sim::Simulation simulation(engine::loadScene(scene));
  expectOneLineError([&] { sim::saveState("/dev/full", simulation); }, "/dev/full");
}

TEST(RobustnessTest, NoGl33FallsBackToHeadlessInOneLine) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "needs a display (CI runs it under Xvfb)";
  // Mesa's llvmpipe capped at OpenGL 2.1: the window cannot get a 3.3 core context
  const std::string scene = engine::assetPath("assets/scenes/tiny_dam_break.json");
  std::string err;
  EXPECT_EQ(runExe("--quiet --frames 2 --scene " + scene, err, "env MESA_GL_VERSION_OVERRIDE=2.1"),
            engine::kExitOk);
  EXPECT_NE(err.find("OpenGL 3.3"), std::string::npos) << err;
  EXPECT_NE(err.find("running headless"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(StateCliTest, SavedAtFrameNLoadedAndContinuedIsBitIdenticalOnOneThread) {
  // fluidplaying mode (splits, merges, the adaptivity's own fields) on one thread: frames 0-8, saved, then
  // loaded and run on to frame 16, against the uninterrupted 16 frames; the saved states must be the same
  // bytes (every particle field, time, counters, parameters, collider poses, app numbers, checksum)
  const fs::path dir = scratch("state_cli");
  const std::string common = "--headless --quiet --threads 1 --mode fluidplaying --scene " +
                             engine::assetPath("assets/scenes/tiny_dam_break.json");
  std::string err;
  const std::string half = (dir / "half.state").string(), resumed = (dir / "resumed.state").string(),
                    whole = (dir / "whole.state").string(), every = (dir / "every.state").string();
  ASSERT_EQ(runExe(common + " --frames 8 --save-state " + half, err), engine::kExitOk) << err;
  ASSERT_EQ(runExe(common + " --frames 8 --load-state " + half + " --save-state " + resumed, err),
            engine::kExitOk)
      << err;
  ASSERT_EQ(runExe(common + " --frames 16 --save-state " + whole + " --save-state-every 5", err),
            engine::kExitOk)
      << err;
  const std::string a = readAll(resumed), b = readAll(whole);
  ASSERT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "the resumed run differs from the uninterrupted one";
  EXPECT_NE(readAll(half), b);
  // the hand tank with a replayed hand: the hand's pose and the replay's clock are part of the state
  const std::string hand = "--headless --quiet --threads 1 --mode uniform-low --scene " +
                           engine::assetPath("assets/scenes/hand_tank.json") + " --hand-script " +
                           engine::assetPath("assets/hands/push.csv");
  ASSERT_EQ(runExe(hand + " --frames 3 --save-state " + half, err), engine::kExitOk) << err;
  ASSERT_EQ(runExe(hand + " --frames 3 --load-state " + half + " --save-state " + resumed, err),
            engine::kExitOk)
      << err;
  ASSERT_EQ(runExe(hand + " --frames 6 --save-state " + whole, err), engine::kExitOk) << err;
  EXPECT_TRUE(readAll(resumed) == readAll(whole))
      << "the resumed hand run differs from the uninterrupted one";
}

TEST(StateCliTest, BadStateFilesAreNamedInOneLineWithExitThree) {
  const fs::path dir = scratch("state_cli_bad");
  const std::string tiny =
      "--headless --quiet --frames 2 --scene " + engine::assetPath("assets/scenes/tiny_dam_break.json");
  std::string err;
  const std::string good = (dir / "good.state").string();
  ASSERT_EQ(runExe(tiny + " --save-state " + good, err), engine::kExitOk) << err;
  const std::string bytes = readAll(good);
  const std::string truncated = (dir / "truncated.state").string(),
                    flipped = (dir / "flipped.state").string(), text = (dir / "text.state").string();
  writeFile(truncated, bytes.substr(0, bytes.size() / 2));
  std::string f = bytes;
  f[f.size() / 3] = char(f[f.size() / 3] ^ 0x40);
  writeFile(flipped, f);
  writeFile(text, "not a state\n");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {tiny + " --load-state " + (dir / "missing.state").string(), "missing.state"},
      {tiny + " --load-state " + dir.string(), dir.string()},
      {tiny + " --load-state " + truncated, "truncated.state"},
      {tiny + " --load-state " + flipped, "flipped.state"},
      {tiny + " --load-state " + text, "text.state"},
      // another scene, and the same scene in another mode
      {"--headless --quiet --frames 2 --scene " + engine::assetPath("assets/scenes/dam_break.json") +
           " --load-state " + good,
       "good.state"},
      {tiny + " --mode uniform-low --load-state " + good, "good.state"},
      {tiny + " --save-state /dev/full", "/dev/full"},
  };
  for (const auto& [args, named] : cases) {
    EXPECT_EQ(runExe(args, err), engine::kExitInput) << args;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << args << ": " << err;
    EXPECT_NE(err.find(named), std::string::npos) << args << ": " << err;
  }
  // --save-state-every needs --save-state: a bad command line
  EXPECT_EQ(runExe(tiny + " --save-state-every 3", err), engine::kExitUsage) << err;
}

namespace {

/// the window's session on the tiny dam break: fixed steps, recovery on, no hand
engine::SessionConfig recoveringConfig() {
  engine::SessionConfig config;
  config.scenePath = engine::assetPath("assets/scenes/tiny_dam_break.json");
  config.mode = "fluidplaying";
  config.fixedStep = true;
  config.recover = true;
  config.hand = false;
  return config;
}

/// one frame of the app loop at 60 Hz
void runFrame(engine::AppSession& session) {
  session.applyRequests();
  session.startSteps(1.0 / 60.0, 1e9);
  session.finishSteps();
}

}  // namespace

TEST(RecoveryTest, ARollbackKeepsAPendingParameterPendingSmall) {
  // a particle radius edited in the panel waits for a reset (not live); snapshots taken after the edit keep
  // it as an edit. A rollback to one of them must leave it pending, not hand it to the running simulation
  // (its particles were built for the old radius, and their supports follow from it)
  engine::SessionConfig config = recoveringConfig();
  engine::AppSession session(config);
  auto frame = [&session] { runFrame(session); };
  const double radius = session.simulation().params().particleRadius;
  session.editParams().particleRadius = 1.25 * radius;
  for (int k = 0; k < 40; ++k)
    frame();
  ASSERT_EQ(session.error(), "");
  ASSERT_TRUE(session.restartPending());
  ASSERT_EQ(session.simulation().params().particleRadius, radius);
  ASSERT_GE(session.snapshots().size(), 1u);
  session.editParams().maxSpeed = sim::ParamTable::sim().at("max_speed").min;
  frame();
  ASSERT_EQ(session.recovery().rollbacks, 1) << session.recovery().message;
  EXPECT_EQ(session.simulation().params().particleRadius, radius)
      << "a pending edit was applied by the rollback";
  EXPECT_EQ(session.editParams().particleRadius, 1.25 * radius) << "the edit is still the panel's";
  EXPECT_TRUE(session.restartPending());
  for (int k = 0; k < 10; ++k)
    frame();
  EXPECT_EQ(session.error(), "");
  EXPECT_EQ(session.simulation().params().particleRadius, radius);
}

TEST(RecoveryTest, AnAbsurdLiveParameterRollsBackToTheLastSnapshotAndRunsOn) {
  // the window's session (recover on): an instability restores the newest in-memory snapshot and halves the
  // time-step cap for a second, instead of pausing with an error; max_speed at its minimum is the absurd
  // value
  engine::SessionConfig config = recoveringConfig();
  engine::AppSession session(config);
  auto frame = [&session] { runFrame(session); };
  for (int k = 0; k < 40; ++k)
    frame();
  ASSERT_EQ(session.error(), "");
  ASSERT_GE(session.snapshots().size(), 2u);
  const std::size_t kept = session.snapshots().size();
  const auto [snapTime, snapBytes] = session.snapshots().back();
  const double dtMax = session.simulation().params().dtMax;
  const double maxSpeed = session.simulation().params().maxSpeed;
  EXPECT_LT(session.simulation().time() - snapTime, engine::AppSession::kSnapshotSpacing + 1e-9);

  session.editParams().maxSpeed =
      sim::ParamTable::sim().at("max_speed").min;  // every moving particle is "runaway"
  frame();
  EXPECT_EQ(session.error(), "") << "recovered, not paused";
  EXPECT_FALSE(session.paused);
  EXPECT_EQ(session.recovery().rollbacks, 1);
  EXPECT_NE(session.recovery().message.find("rolled back"), std::string::npos) << session.recovery().message;
  // the state is the snapshot's: every particle field, time and step counter, against the snapshot decoded
  // into a fresh simulation of the same scene
  const sim::Simulation& now = session.simulation();
  sim::Simulation expected(now.scene());
  sim::decodeState(snapBytes, expected);
  EXPECT_EQ(now.time(), snapTime);
  EXPECT_EQ(now.stepCount(), expected.stepCount());
  ASSERT_EQ(now.particles().size(), expected.particles().size());
  EXPECT_TRUE(now.particles().x == expected.particles().x);
  EXPECT_TRUE(now.particles().v == expected.particles().v);
  EXPECT_TRUE(now.particles().m == expected.particles().m);
  // the absurd edit is undone with the state, and the step is capped at half for a second
  EXPECT_EQ(now.params().maxSpeed, maxSpeed);
  EXPECT_EQ(session.editParams().maxSpeed, maxSpeed);
  EXPECT_DOUBLE_EQ(now.params().dtMax, 0.5 * dtMax);
  EXPECT_EQ(session.snapshots().size(), kept - 1) << "the restored snapshot leaves the ring";

  // runs on: no NaN, time advances, the cap ends after its second
  double maxStep = 0.0;
  for (int k = 0; k < 70; ++k) {
    frame();
    ASSERT_EQ(session.error(), "") << "frame " << k;
    if (session.simulation().time() < snapTime + 0.95)
      maxStep = std::max(maxStep, session.simulation().lastStep().dt);
    for (const sim::Vec3& x : session.simulation().particles().x)
      ASSERT_TRUE(x.allFinite());
  }
  EXPECT_EQ(session.recovery().rollbacks, 1);
  EXPECT_LE(maxStep, 0.5 * dtMax * (1 + 1e-6));
  EXPECT_GT(session.simulation().time(), snapTime + 1.1);
  EXPECT_EQ(session.simulation().params().dtMax, dtMax) << "the cap ends after a second";

  // without snapshots (an instability in the first frame) the scene is reset, still no pause
  engine::AppSession fresh(config);
  fresh.editParams().maxSpeed = sim::ParamTable::sim().at("max_speed").min;
  runFrame(fresh);
  EXPECT_EQ(fresh.error(), "");
  EXPECT_EQ(fresh.recovery().rollbacks, 1);
  EXPECT_NE(fresh.recovery().message.find("reset"), std::string::npos) << fresh.recovery().message;
  EXPECT_EQ(fresh.simulation().time(), 0.0);
  EXPECT_EQ(fresh.simulation().params().maxSpeed, maxSpeed);

  // a headless session (recover off) still stops with the report
  config.recover = false;
  engine::AppSession headless(config);
  headless.editParams().maxSpeed = sim::ParamTable::sim().at("max_speed").min;
  runFrame(headless);
  EXPECT_NE(headless.error().find("max_speed"), std::string::npos) << headless.error();
  EXPECT_TRUE(headless.paused);
}

}  // namespace
