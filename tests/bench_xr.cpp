/// fp_bench_xr: the headset mode's frame loop (engine/xr_app, as `fluidplaying --xr --no-window` runs it)
/// against the test OpenXR runtime (tests/xr/runtime) in real time at 90 Hz, with two 1440 x 1600 eyes and
/// with two 720 x 800 eyes (or --sizes). The runtime logs every frame's calls (FP_XR_FRAME_LOG): the time
/// blocked in xrWaitFrame, each eye's drawing (colour image acquired to released; the runtime waits for the
/// drawing on release, as a compositor does), the submit (the right eye released to xrEndFrame returned) and
/// the display periods without a frame (missed); the solver's wall time per frame on the TBB workers (running
/// while the frame waits and draws) and the real-time factor come from the run's statistics. The first
/// frames (shaders compiled, caches cold) are left out. Prints one table row per eye size and the same as
/// CSV.
///
///   fp_bench_xr [--frames N] [--warmup N] [--scene FILE] [--mode NAME] [--sizes WxH,...] [--period-ns N]
///               [--csv FILE] [--help]

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/cli.h"
#include "engine/xr_app.h"
#include "engine/xr_program.h"

namespace {

struct Row {
  std::string size;
  int frames = 0;            // frames measured (after the warm-up)
  double frameMs = 0;        // between consecutive xrWaitFrame returns
  double waitMs = 0;         // blocked in xrWaitFrame
  double simMs = 0;          // solver wall time per frame, on the workers
  double eyeMs[2] = {0, 0};  // drawing each eye
  double submitMs = 0;       // right eye released -> xrEndFrame returned
  long missed = 0;           // display periods without a frame, after the warm-up
  double realTime = 0;       // simulated / displayed time
};

struct LogLine {
  long long display = 0, end = 0, waitCalled = 0, waitReturned = 0, acquire[2] = {0, 0}, release[2] = {0, 0};
};

Row runSize(const std::string& size, int frames, int warmup, const std::string& scene,
            const std::string& mode, long long period) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "fp_bench_xr" / size;
  std::filesystem::create_directories(dir);
  const std::string log = (dir / "frames.txt").string(), stats = (dir / "runtime.txt").string(),
                    json = (dir / "stats.json").string();
  std::filesystem::remove(log);
  std::string sizeArg = size;
  sizeArg[sizeArg.find('x')] = ',';
  setenv("XR_RUNTIME_JSON", FP_TEST_RUNTIME_JSON, 1);
  unsetenv("XR_ENABLE_API_LAYERS");
  unsetenv("FP_XR_VIRTUAL_TIME");
  setenv("FP_XR_SIZE", sizeArg.c_str(), 1);
  setenv("FP_XR_PERIOD_NS", std::to_string(period).c_str(), 1);
  setenv("FP_XR_FRAME_LOG", log.c_str(), 1);
  setenv("FP_XR_STATS", stats.c_str(), 1);
  setenv("FP_XR_HEAD", "0,1.1,0,0", 1);  // the tank on its table in view
  setenv("FP_XR_HANDS", FP_SOURCE_DIR "/assets/hands/two_hands_push.csv", 1);
  setenv("FP_XR_HANDS_OFFSET", "0,0.75,-0.5", 1);
  std::vector<std::string> args = {"--xr",    "--no-window", "--frames", std::to_string(frames + warmup),
                                   "--scene", scene,         "--stats",  json,
                                   "--quiet"};
  if (!mode.empty())
    args.insert(args.end(), {"--mode", mode});
  std::ostringstream quiet;
  fp::engine::runXrApp(fp::engine::parseCommandLine(args), quiet);

  std::vector<LogLine> lines;
  std::ifstream in(log);
  for (std::string text; std::getline(in, text);) {
    std::istringstream f(text);
    LogLine l;
    if (f >> l.display >> l.end >> l.waitCalled >> l.waitReturned >> l.acquire[0] >> l.release[0] >>
        l.acquire[1] >> l.release[1])
      lines.push_back(l);
  }
  Row r;
  r.size = size;
  for (std::size_t i = std::size_t(std::max(warmup, 1)); i < lines.size(); ++i) {
    const LogLine& l = lines[i];
    ++r.frames;
    r.frameMs += 1e-6 * double(l.waitReturned - lines[i - 1].waitReturned);
    r.waitMs += 1e-6 * double(l.waitReturned - l.waitCalled);
    for (int e = 0; e < 2; ++e)
      r.eyeMs[e] += 1e-6 * double(l.release[e] - l.acquire[e]);
    r.submitMs += 1e-6 * double(l.end - l.release[1]);
    r.missed += (l.display - lines[i - 1].display) / period - 1;
  }
  if (r.frames) {
    for (double* v : {&r.frameMs, &r.waitMs, &r.eyeMs[0], &r.eyeMs[1], &r.submitMs})
      *v /= r.frames;
  }
  std::ifstream js(json);
  const nlohmann::json s = nlohmann::json::parse(js, nullptr, false);
  if (s.is_object() && !lines.empty()) {
    double stepSeconds = 0.0;
    for (const auto& [phase, seconds] : s.at("phase_seconds").items())
      stepSeconds += double(seconds);
    r.simMs = 1e3 * stepSeconds / double(lines.size());
    r.realTime = double(s.at("sim_seconds")) / (double(lines.size()) * double(period) * 1e-9);
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fp_bench_xr: the headset frame loop against the test OpenXR runtime"};
  int frames = 30, warmup = 5;
  std::string scene = FP_SOURCE_DIR "/assets/scenes/hand_tank.json", mode, csvPath;
  std::vector<std::string> sizes = {"1440x1600", "720x800"};
  long long period = 11111111;
  app.add_option("--frames", frames, "frames measured per eye size (after the warm-up)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--warmup", warmup, "frames left out at the start")->check(CLI::Range(0, 1000));
  app.add_option("--scene", scene, "scene JSON")->check(CLI::ExistingFile);
  app.add_option("--mode", mode, "resolution mode (default: the scene's)");
  app.add_option("--sizes", sizes, "eye sizes WxH")->delimiter(',');
  app.add_option("--period-ns", period, "display period [ns] (90 Hz: 11111111)")
      ->check(CLI::Range(1000000LL, 1000000000LL));
  app.add_option("--csv", csvPath, "also write the CSV to this file");
  CLI11_PARSE(app, argc, argv);
  std::vector<Row> rows;
  try {
    for (const std::string& size : sizes) {
      if (size.find('x') == std::string::npos) {
        std::cerr << "fp_bench_xr: --sizes: expected WxH, got " << size << "\n";
        return 2;
      }
      rows.push_back(runSize(size, frames, warmup, scene, mode, period));
    }
  } catch (const std::exception& e) {
    std::cerr << "fp_bench_xr: " << e.what() << "\n";
    return 1;
  }
  std::printf("fp_bench_xr: %s, %.1f Hz, %d frames after %d warm-up frames; mean ms per frame\n",
              scene.c_str(), 1e9 / double(period), frames, warmup);
  std::printf("%-10s %7s %8s %8s %9s %8s %8s %8s %7s %7s\n", "eyes", "frames", "frame", "wait", "sim(wrk)",
              "eye 0", "eye 1", "submit", "missed", "rtf");
  std::ostringstream csv;
  csv << "eyes,frames,frame_ms,wait_ms,sim_ms,eye0_ms,eye1_ms,submit_ms,missed,real_time_factor\n";
  for (const Row& r : rows) {
    std::printf("%-10s %7d %8.2f %8.2f %9.2f %8.2f %8.2f %8.2f %7ld %7.3f\n", r.size.c_str(), r.frames,
                r.frameMs, r.waitMs, r.simMs, r.eyeMs[0], r.eyeMs[1], r.submitMs, r.missed, r.realTime);
    csv << r.size << ',' << r.frames << ',' << r.frameMs << ',' << r.waitMs << ',' << r.simMs << ','
        << r.eyeMs[0] << ',' << r.eyeMs[1] << ',' << r.submitMs << ',' << r.missed << ',' << r.realTime
        << '\n';
  }
  std::cout << "\n" << csv.str();
  if (!csvPath.empty())
    std::ofstream(csvPath) << csv.str();
  return 0;
}
