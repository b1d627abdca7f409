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
#include <sstream>
#include <string>

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

}  // namespace
