// The command line and the headless runner: bad input gives a usage error or a clear message and a non-zero
// exit; a good run prints a summary and writes the stats JSON with the documented keys, and PLY frames.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "engine/cli.h"
#include "engine/headless_runner.h"
#include "engine/scene_loader.h"
#include "render/camera.h"
#include "render/render_settings.h"
#include "sim/scene.h"
#include "tests/temp_path.h"

using namespace fp::engine;

namespace {
std::string scene(const std::string& name) {
  return std::string(FP_SOURCE_DIR) + "/assets/scenes/" + name;
}

int runExe(const std::string& args) {
  const std::string cmd = std::string(FP_FLUIDPLAYING_EXE) + " " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct ExeRun {
  int code = -1;
  std::string out;
  std::vector<std::string> errLines;
};

// runs the executable with `args`, keeping stdout and the lines of stderr
ExeRun runExeOutput(const std::string& args) {
  // one file pair per test: ctest runs the tests of this suite in parallel processes
  const std::string base = fp::test::tempPath("run");
  const std::string cmd =
      std::string(FP_FLUIDPLAYING_EXE) + " " + args + " > " + base + ".out 2> " + base + ".err";
  const int status = std::system(cmd.c_str());
  ExeRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream out(base + ".out");
  r.out.assign(std::istreambuf_iterator<char>(out), std::istreambuf_iterator<char>());
  std::ifstream err(base + ".err");
  for (std::string line; std::getline(err, line);)
    r.errLines.push_back(line);
  return r;
}

std::string messageOf(const std::vector<std::string>& args) {
  try {
    parseCommandLine(args);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(CliTest, ParsesOptions) {
  const CliOptions o =
      parseCommandLine({"--headless", "--scene", "a.json", "--frames", "10", "--threads", "1", "--seed", "42",
                        "--stats", "s.json", "--export", "out", "--quiet"});
  EXPECT_TRUE(o.headless);
  EXPECT_EQ(o.scenePath, "a.json");
  EXPECT_EQ(o.frames.value(), 10);
  EXPECT_EQ(o.threads, 1);
  EXPECT_EQ(o.seed.value(), 42u);
  EXPECT_EQ(o.statsPath, "s.json");
  EXPECT_EQ(o.exportDir, "out");
  EXPECT_TRUE(o.quiet);
  EXPECT_FALSE(parseCommandLine({}).scenePath.empty());  // the default scene
}

TEST(CliTest, RejectsBadInput) {
  EXPECT_THROW(parseCommandLine({"--bogus"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--frames"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--frames", "ten"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--frames", "0"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--threads", "2.5"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--sim-time", "-1"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--frames", "3", "--sim-time", "1"}), std::invalid_argument);
  try {
    parseCommandLine({"--frames", "ten"});
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--frames"), std::string::npos);
  }
}

TEST(CliTest, ParsesTheModeAndRejectsUnknownModes) {
  EXPECT_EQ(parseCommandLine({"--mode", "fluidplaying"}).mode, "fluidplaying");
  EXPECT_EQ(parseCommandLine({"--mode", "uniform-low"}).mode, "uniform-low");
  EXPECT_TRUE(parseCommandLine({}).mode.empty());  // the scene's mode
  EXPECT_THROW(parseCommandLine({"--mode", "adaptive"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--mode"}), std::invalid_argument);
  try {
    parseCommandLine({"--mode", "adaptive"});
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("uniform-low"), std::string::npos) << e.what();
  }
  EXPECT_EQ(runExe("--headless --mode adaptive"), kExitUsage);
}

TEST(CliTest, ParsesRenderOptions) {
  const CliOptions o =
      parseCommandLine({"--render", "--out", "img", "--width", "640", "--height", "360", "--color", "speed",
                        "--highlight-time", "0.25", "--no-spray", "--shaders", "sh"});
  EXPECT_TRUE(o.render);
  EXPECT_TRUE(o.headless);  // --render implies it
  EXPECT_EQ(o.outDir, "img");
  EXPECT_EQ(o.width, 640);
  EXPECT_EQ(o.height, 360);
  EXPECT_EQ(o.view, "particles");  // --color implies the particle view
  EXPECT_EQ(o.colorField, "speed");
  EXPECT_DOUBLE_EQ(o.highlightTime.value(), 0.25);
  EXPECT_TRUE(o.noSpray);
  EXPECT_EQ(o.shaderDir, "sh");
  const CliOptions d = parseCommandLine({"--headless", "--render", "--out", "img"});
  EXPECT_EQ(d.width, 1280);
  EXPECT_EQ(d.height, 720);
  EXPECT_EQ(d.view, "fluid");
  EXPECT_FALSE(parseCommandLine({}).render);
}

TEST(CliTest, RejectsBadRenderOptions) {
  EXPECT_THROW(parseCommandLine({"--render"}), std::invalid_argument);                      // no --out
  EXPECT_THROW(parseCommandLine({"--out", "img"}), std::invalid_argument);                  // no --render
  EXPECT_THROW(parseCommandLine({"--headless", "--width", "640"}), std::invalid_argument);  // no --render
  EXPECT_EQ(parseCommandLine({"--width", "640"}).width, 640);  // the window's size
  EXPECT_THROW(parseCommandLine({"--render", "--out", "i", "--width", "8"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--render", "--out", "i", "--height", "1e5"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--render", "--out", "i", "--view", "wire"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--render", "--out", "i", "--color", "mood"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--render", "--out", "i", "--view", "fluid", "--color", "nu"}),
               std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--render", "--out", "i", "--highlight-time", "-1"}), std::invalid_argument);
  EXPECT_EQ(runExe("--headless --render"), kExitUsage);
}

TEST(CliTest, ExitCodesOfTheExecutable) {
  EXPECT_EQ(runExe("--help"), kExitOk);
  EXPECT_EQ(runExe("--no-such-flag"), kExitUsage);
  EXPECT_EQ(runExe("--headless --scene /nonexistent/scene.json"), kExitInput);
  const std::string bad = fp::test::tempPath("bad_scene.json");
  std::ofstream(bad) << "{\"domain\": 3}";
  EXPECT_EQ(runExe("--headless --quiet --scene " + bad), kExitInput);
}

TEST(CliTest, HelpListsEveryOptionAndExitsZero) {
  const ExeRun r = runExeOutput("--help");
  EXPECT_EQ(r.code, kExitOk);
  EXPECT_TRUE(r.errLines.empty());
  for (const char* option : {"--headless",   "--scene",          "--mode",          "--frames",
                             "--sim-time",   "--threads",        "--seed",          "--set",
                             "--quiet",      "--hand-script",    "--hand-size",     "--fixed-step",
                             "--time-scale", "--screenshot",     "--record-frames", "--fullscreen",
                             "--no-panel",   "--stats",          "--export",        "--render",
                             "--out",        "--width",          "--height",        "--view",
                             "--color",      "--highlight-time", "--no-spray",      "--shaders",
                             "Exit codes"}) {
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  }
  EXPECT_EQ(runExe("-h"), kExitOk);
  EXPECT_TRUE(parseCommandLine({"--help"}).help);
}

TEST(CliTest, ABadCommandLineIsExitTwoAndOneLine) {
  for (const char* args : {"--no-such-flag", "--frames ten", "--frames", "--set dt_max=9", "--set nope=1",
                           "--set dt_max", "--seed -1", "--headless --render", "stray"}) {
    const ExeRun r = runExeOutput(std::string("--headless --quiet ") + args);
    EXPECT_EQ(r.code, kExitUsage) << args;
    ASSERT_EQ(r.errLines.size(), 1u) << args;
    EXPECT_EQ(r.errLines[0].rfind("fluidplaying: ", 0), 0u) << r.errLines[0];
    EXPECT_NE(r.errLines[0].find("--help"), std::string::npos) << r.errLines[0];
    EXPECT_TRUE(r.out.empty()) << args;
  }
}

TEST(CliTest, TheBenchmarksShareTheCommandLine) {
  // every executable: --help exits 0, a bad option or setting exits 2 with one line naming the program
  std::istringstream exes(FP_BENCH_EXES);
  for (std::string exe; exes >> exe;) {
    const std::string name = std::filesystem::path(exe).filename().string();
    const std::string err = fp::test::tempPath(name + ".err");
    EXPECT_EQ(std::system((exe + " --help > /dev/null 2> " + err).c_str()), 0) << name;
    for (const char* args : {"--no-such-flag", "--set no_such_key=1"}) {
      const int status = std::system((exe + " " + args + " > /dev/null 2> " + err).c_str());
      ASSERT_TRUE(WIFEXITED(status));
      EXPECT_EQ(WEXITSTATUS(status), kExitUsage) << name << " " << args;
      std::ifstream in(err);
      std::vector<std::string> lines;
      for (std::string line; std::getline(in, line);)
        lines.push_back(line);
      ASSERT_EQ(lines.size(), 1u) << name << " " << args;
      EXPECT_EQ(lines[0].rfind(name + ": ", 0), 0u) << lines[0];
    }
  }
}

namespace {

/// the path of one benchmark executable of FP_BENCH_EXES by its file name, "" if it is not there
std::string benchExe(const std::string& name) {
  std::istringstream exes(FP_BENCH_EXES);
  for (std::string e; exes >> e;)
    if (std::filesystem::path(e).filename() == name)
      return e;
  return "";
}

}  // namespace

TEST(CliTest, BenchModesReportsAModeWhoseStillRunWentUnstable) {
  // The still run that measures a mode's resting level goes unstable (every falling particle is above
  // max_speed): a row that says so and exit code 4, not an abort from an uncaught exception.
  const std::string exe = benchExe("fp_bench_modes");
  ASSERT_FALSE(exe.empty());
  const std::string out = fp::test::tempPath("bench_modes_unstable.out");
  const int status =
      std::system((exe + " --scene " + scene("tiny_dam_break.json") +
                   " --modes surface --sim-time 0.05 --rest-time 0.2 --set max_speed=0.1 > " + out + " 2>&1")
                      .c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "ended by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 4);
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("surface: still run: unstable at step"), std::string::npos) << text;
}

TEST(CliTest, BenchScalingRunsTheDefaultHandTankOncePerThreadCount) {
  const std::string exe = benchExe("fp_bench");
  ASSERT_FALSE(exe.empty());
  const std::string out = fp::test::tempPath("bench_scaling.out");
  const std::string csvPath = fp::test::tempPath("bench_scaling.csv");
  std::filesystem::remove(csvPath);
  const std::string run =
      exe + " --scaling --threads 1,2 --hand-time 0.02 --csv " + csvPath + " > " + out + " 2>/dev/null";
  ASSERT_EQ(std::system(run.c_str()), 0) << run;
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // the default tank, one row per count, the speed-up over the first
  EXPECT_NE(text.find("\nhand_tank_r5mm,1,"), std::string::npos) << text;
  EXPECT_NE(text.find("\nhand_tank_r5mm,2,"), std::string::npos) << text;
  EXPECT_NE(text.find("  1 threads:"), std::string::npos) << text;
  EXPECT_NE(text.find("speed-up  1.00"), std::string::npos) << text;
  EXPECT_NE(text.find("  2 threads:"), std::string::npos) << text;
  std::ifstream csv(csvPath);
  std::vector<std::string> lines;
  for (std::string line; std::getline(csv, line);)
    lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[1].rfind("hand_tank_r5mm,1,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[2].rfind("hand_tank_r5mm,2,", 0), 0u) << lines[2];
  // one mode a run
  const int both = std::system((exe + " --suite --scaling > /dev/null 2>&1").c_str());
  ASSERT_TRUE(WIFEXITED(both));
  EXPECT_EQ(WEXITSTATUS(both), kExitUsage);
}

TEST(CliTest, SetIsCheckedByTheParameterTable) {
  const CliOptions o =
      parseCommandLine({"--set", "dt_max=0.002", "--set", "gravity=0,-5,0", "--set=warm_start=0"});
  EXPECT_EQ(o.sets, (std::vector<std::string>{"dt_max=0.002", "gravity=0,-5,0", "warm_start=0"}));
  // the table's own messages: unknown key, range, type, form
  EXPECT_NE(messageOf({"--set", "dt_maxx=1"}).find("dt_maxx"), std::string::npos);
  EXPECT_NE(messageOf({"--set", "dt_max=9"}).find("dt_max"), std::string::npos);
  EXPECT_NE(messageOf({"--set", "dt_max=9"}).find("range"), std::string::npos)
      << messageOf({"--set", "dt_max=9"});
  EXPECT_NE(messageOf({"--set", "max_iterations=2.5"}).find("max_iterations"), std::string::npos);
  EXPECT_NE(messageOf({"--set", "gravity=1,2"}).find("gravity"), std::string::npos);
  EXPECT_NE(messageOf({"--set", "=3"}).find("KEY=VALUE"), std::string::npos);
  // applied to a scene in order, then the relations are checked
  fp::sim::SceneDesc desc;
  overrideScene(desc, {"surface", 9, {"dt_max=0.002", "gravity=0,-5,0", "warm_start=false"}});
  EXPECT_EQ(desc.mode, fp::sim::AdaptivityMode::Surface);
  EXPECT_EQ(desc.params.seed, 9u);
  EXPECT_DOUBLE_EQ(desc.params.dtMax, 0.002);
  EXPECT_DOUBLE_EQ(desc.params.gravity[1], -5.0);
  EXPECT_FALSE(desc.params.warmStart);
  EXPECT_THROW(overrideScene(desc, {"", std::nullopt, {"dt_min=0.009"}}),
               std::invalid_argument);  // > dt_max
  // a relation broken with the scene's own values is a bad command line too
  EXPECT_EQ(
      runExe("--headless --quiet --frames 1 --scene " + scene("tiny_dam_break.json") + " --set dt_min=0.009"),
      kExitUsage);
}

TEST(CliTest, RenderOptionsGoThroughTheRenderSettingsTable) {
  // --set sorts its settings by table; the render options are aliases of render settings
  const CliOptions o = parseCommandLine({"--render", "--out", "i", "--set", "view=particles", "--set",
                                         "dt_max=0.002", "--set", "filter_iterations=3"});
  EXPECT_EQ(o.sets, (std::vector<std::string>{"dt_max=0.002"}));
  EXPECT_EQ(o.renderSets, (std::vector<std::string>{"view=particles", "filter_iterations=3"}));
  fp::render::RenderSettings settings;
  applyRenderOptions(o, settings);
  EXPECT_EQ(settings.view, fp::render::RenderSettings::View::Particles);
  EXPECT_EQ(settings.filterIterations, 3);
  fp::render::RenderSettings aliased;
  applyRenderOptions(parseCommandLine({"--color", "speed", "--no-spray", "--highlight-time", "0"}), aliased);
  EXPECT_EQ(aliased.view, fp::render::RenderSettings::View::Particles);
  EXPECT_EQ(aliased.colorField, fp::render::ColorField::Speed);
  EXPECT_FALSE(aliased.showSpray);
  EXPECT_FALSE(aliased.highlightSplits);
  fp::render::RenderSettings longer;
  applyRenderOptions(parseCommandLine({"--highlight-time", "2"}), longer);
  EXPECT_TRUE(longer.highlightSplits);
  EXPECT_FLOAT_EQ(longer.highlightDuration, 2.0f);
  // the table's messages and ranges
  EXPECT_NE(messageOf({"--set", "view=wire"}).find("fluid or particles"), std::string::npos);
  EXPECT_NE(messageOf({"--set", "viewz=fluid"}).find("did you mean view"), std::string::npos);
  EXPECT_THROW(parseCommandLine({"--highlight-time", "20"}), std::invalid_argument);  // the table's max
  EXPECT_THROW(parseCommandLine({"--headless", "--set", "view=particles"}), std::invalid_argument);
}

TEST(CliTest, SetAndSeedReachTheRun) {
  CliOptions o = parseCommandLine({"--headless", "--quiet", "--frames", "2", "--scene",
                                   scene("tiny_dam_break.json"), "--seed", "77", "--set", "max_speed=40"});
  std::ostringstream out, progress;
  const RunSummary s = runHeadless(o, out, progress);
  EXPECT_EQ(s.seed, 77u);
  EXPECT_EQ(s.status, "ok");
  EXPECT_EQ(runExe("--headless --quiet --frames 1 --scene " + scene("tiny_dam_break.json") +
                   " --set max_speed=40 --set seed=3"),
            kExitOk);
}

TEST(CliTest, ParsesAppOptions) {
  const CliOptions o = parseCommandLine({"--hand-script", "h.csv", "--fixed-step", "--time-scale", "0.5",
                                         "--screenshot", "s.png", "--record-frames", "rec", "--hand-size",
                                         "1.5", "--frames", "10", "--fullscreen", "--no-panel"});
  EXPECT_FALSE(o.headless);
  EXPECT_EQ(o.handScript, "h.csv");
  EXPECT_TRUE(o.fixedStep);
  EXPECT_DOUBLE_EQ(o.timeScale, 0.5);
  EXPECT_EQ(o.screenshot, "s.png");
  EXPECT_EQ(o.recordDir, "rec");
  EXPECT_DOUBLE_EQ(o.handScale, 1.5);
  EXPECT_EQ(o.frames.value(), 10);
  EXPECT_TRUE(o.fullscreen);
  EXPECT_TRUE(o.noPanel);
  // the window's default scene is the hand tank, the headless mode's the dam break
  EXPECT_NE(parseCommandLine({}).scenePath.find("hand_tank.json"), std::string::npos);
  EXPECT_TRUE(parseCommandLine({}).sceneDefaulted);
  EXPECT_FALSE(parseCommandLine({"--scene", "x.json"}).sceneDefaulted);
  // the window's default plays at r = 5 mm, where a finger spans a particle; software OpenGL gets the coarse
  // tank (7.9 mm), the same tank otherwise
  const fp::sim::SceneDesc fine = loadScene(parseCommandLine({}).scenePath);
  const fp::sim::SceneDesc coarse = loadScene(softwareGlScenePath());
  EXPECT_DOUBLE_EQ(fine.params.particleRadius, 0.005);
  EXPECT_DOUBLE_EQ(coarse.params.particleRadius, 0.0079);
  EXPECT_EQ(fine.mode, coarse.mode);
  EXPECT_EQ(fine.domain.min(), coarse.domain.min());
  EXPECT_EQ(fine.domain.max(), coarse.domain.max());
  EXPECT_EQ(fine.simTime, coarse.simTime);
  EXPECT_EQ(fine.frameRate, coarse.frameRate);
  ASSERT_EQ(fine.fluid.size(), coarse.fluid.size());
  for (std::size_t k = 0; k < fine.fluid.size(); ++k) {
    EXPECT_EQ(fine.fluid[k].box.min(), coarse.fluid[k].box.min());
    EXPECT_EQ(fine.fluid[k].box.max(), coarse.fluid[k].box.max());
  }
  ASSERT_EQ(fine.colliders.size(), coarse.colliders.size());
  for (std::size_t k = 0; k < fine.colliders.size(); ++k) {
    EXPECT_EQ(fine.colliders[k].halfExtents, coarse.colliders[k].halfExtents);
    EXPECT_EQ(fine.colliders[k].position, coarse.colliders[k].position);
    EXPECT_EQ(fine.colliders[k].headroom, coarse.colliders[k].headroom);
    EXPECT_EQ(fine.colliders[k].container, coarse.colliders[k].container);
  }
  EXPECT_TRUE(isSoftwareGl("4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_TRUE(isSoftwareGl("3.3 (Core Profile) Mesa 22.3.6, softpipe"));
  EXPECT_TRUE(isSoftwareGl("2.1 Mesa 22.3.6, Software Rasterizer"));
  EXPECT_TRUE(isSoftwareGl("4.1 Metal - 83.1, Apple Software Renderer"));
  EXPECT_TRUE(isSoftwareGl("1.1.0, GDI Generic"));
  EXPECT_FALSE(isSoftwareGl("4.6.0 NVIDIA 535.183.01, NVIDIA GeForce RTX 3060/PCIe/SSE2"));
  EXPECT_FALSE(isSoftwareGl("4.6 (Core Profile) Mesa 22.3.6, AMD Radeon RX 6600 (navi23, LLVM 15.0.6)"));
  EXPECT_NE(parseCommandLine({"--headless"}).scenePath.find("dam_break.json"), std::string::npos);
  // the hand script also works headless; window-only options do not
  EXPECT_EQ(parseCommandLine({"--headless", "--hand-script", "h.csv"}).handScript, "h.csv");
  EXPECT_THROW(parseCommandLine({"--headless", "--screenshot", "s.png"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--headless", "--fixed-step"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--sim-time", "1"}), std::invalid_argument);  // the window runs until closed
  EXPECT_THROW(parseCommandLine({"--time-scale", "10"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--hand-size", "0.1"}), std::invalid_argument);
  EXPECT_THROW(parseCommandLine({"--hand-script"}), std::invalid_argument);
}

TEST(CliTest, WindowWithoutDisplayFallsBackToHeadlessInOneLine) {
  const std::string err = fp::test::tempPath("no_display.txt");
  const std::string cmd = std::string("env -u DISPLAY -u WAYLAND_DISPLAY ") + FP_FLUIDPLAYING_EXE +
                          " --quiet --frames 2 --scene " + scene("tiny_dam_break.json") + " > /dev/null 2> " +
                          err;
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), kExitOk);
  std::ifstream in(err);
  std::string line, rest;
  std::getline(in, line);
  EXPECT_NE(line.find("no display"), std::string::npos) << line;
  EXPECT_NE(line.find("running headless"), std::string::npos) << line;
  EXPECT_FALSE(std::getline(in, rest)) << "more than one line: " << rest;
}

TEST(CliTest, HeadlessHandReplayRunsAndRejectsABadScript) {
  const std::string hands = std::string(FP_SOURCE_DIR) + "/assets/hands/";
  EXPECT_EQ(runExe("--headless --quiet --frames 2 --scene " + scene("hand_tank.json") +
                   " --mode uniform-low " + "--hand-script " + hands + "push.csv"),
            kExitOk);
  const std::string bad = fp::test::tempPath("bad_hand.csv");
  std::ofstream(bad) << "time,x\n0,1\n";
  EXPECT_EQ(runExe("--headless --quiet --frames 2 --scene " + scene("tiny_dam_break.json") +
                   " --hand-script " + bad),
            kExitInput);
}

TEST(HeadlessRunnerTest, WritesSummaryStatsAndFramesSmall) {
  const std::string dir = fp::test::tempPath("frames");
  std::filesystem::remove_all(dir);
  CliOptions o;
  o.headless = true;
  o.quiet = true;
  o.scenePath = scene("tiny_dam_break.json");
  o.frames = 6;
  o.threads = 1;
  o.exportDir = dir + "/frames";
  o.statsPath = dir + "/stats.json";
  std::ostringstream out, progress;
  const RunSummary s = runHeadless(o, out, progress);
  EXPECT_EQ(s.status, "ok");
  EXPECT_EQ(s.frames, 6);
  EXPECT_NEAR(s.simSeconds, 0.1, 0.01);
  EXPECT_GT(s.steps, 10u);
  EXPECT_EQ(s.massInitial, s.massFinal);
  writeStatsJson(o.statsPath, s);
  std::ifstream in(o.statsPath);
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* key : {"particles_mean", "particles_max", "steps", "sim_seconds", "wall_seconds",
                          "us_per_particle_step", "density_error_mean", "density_error_max", "max_speed",
                          "max_speed_time", "mass_initial", "mass_final"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  // the water of the tiny dam break falls: its fastest particle over the 0.1 s, some time into it
  EXPECT_EQ(j["max_speed"].get<double>(), s.maxSpeed);
  EXPECT_GT(s.maxSpeed, 0.3);
  EXPECT_LT(s.maxSpeed, 5.0);
  EXPECT_GT(s.maxSpeedTime, 0.0);
  EXPECT_LE(s.maxSpeedTime, s.simSeconds);
  EXPECT_EQ(j["steps"].get<std::uint64_t>(), s.steps);
  EXPECT_EQ(j["particles_max"].get<std::size_t>(), s.particlesMax);
  for (int f = 0; f <= 6; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.ply", f);
    EXPECT_TRUE(std::filesystem::exists(dir + "/frames/" + name)) << name;
  }
  std::ostringstream summary;
  printSummary(summary, s);
  EXPECT_NE(summary.str().find("us per particle-step"), std::string::npos);
  EXPECT_NE(summary.str().find("fastest particle"), std::string::npos);
  EXPECT_THROW(writeStatsJson("/nonexistent/dir/stats.json", s), fp::sim::InputError);
}

TEST(HeadlessRunnerTest, TheAppLoopStepsLikeAPlainLoop) {
  // the headless run goes through runAppLoop in fixed frames; the simulation must step exactly as a plain
  // loop over Simulation::step to the same end, and the figures be those of the same state
  const ThreadLimit threads(1);
  CliOptions o;
  o.headless = true;
  o.quiet = true;
  o.scenePath = scene("tiny_dam_break.json");
  o.mode = "fluidplaying";
  o.simTime = 0.11;  // not a whole number of frames: the last frame stops at the end
  std::ostringstream out, progress;
  int callbacks = 0;
  const RunSummary s = runHeadless(
      o, out, progress, [&](int frame, const fp::sim::Simulation&, const fp::sim::SplashParticles&) {
        EXPECT_EQ(frame, callbacks++);
      });
  fp::sim::SceneDesc desc = fp::engine::loadScene(o.scenePath);
  desc.mode = fp::sim::AdaptivityMode::FluidPlaying;
  fp::sim::Simulation plain(desc);
  while (plain.time() < 0.11 - 1e-12)
    plain.step();
  // the app loop ends each frame's steps with the search of the next step (Simulation::prepareNeighbors),
  // which reorders the particles: the sums below then add them in the same order
  plain.prepareNeighbors();
  EXPECT_EQ(s.steps, plain.stepCount());
  EXPECT_EQ(s.simSeconds, plain.time());
  EXPECT_EQ(s.particlesFinal, plain.particles().size());
  EXPECT_EQ(s.momentumFinal, plain.totalMomentum());
  EXPECT_EQ(s.massFinal, plain.totalMass());
  EXPECT_EQ(s.frames, 6);  // 0.11 s at 60 Hz: six whole frames after the initial state
  EXPECT_EQ(callbacks, 7);
}

TEST(CameraTest, FramesABoxAndProjectsItsCentreToTheMiddle) {
  fp::render::OrbitCamera cam;
  cam.frame(Eigen::Vector3f(-1, 0, -0.5f), Eigen::Vector3f(1, 1, 0.5f), 16.0f / 9.0f);
  const Eigen::Vector4f c = cam.projection(16.0f / 9.0f) * cam.view() * Eigen::Vector4f(0, 0.5f, 0, 1);
  EXPECT_NEAR(c.x() / c.w(), 0.0f, 1e-5f);
  EXPECT_NEAR(c.y() / c.w(), 0.0f, 1e-5f);
  // every corner of the box lands inside the view
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector4f p(k & 1 ? 1.0f : -1.0f, k & 2 ? 1.0f : 0.0f, k & 4 ? 0.5f : -0.5f, 1.0f);
    const Eigen::Vector4f q = cam.projection(16.0f / 9.0f) * cam.view() * p;
    EXPECT_LE(std::abs(q.x() / q.w()), 1.0f);
    EXPECT_LE(std::abs(q.y() / q.w()), 1.0f);
    EXPECT_GT(q.w(), 0.0f);
  }
}
