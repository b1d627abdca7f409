// fp_bench_app: the desktop app's frame time split into simulation, rendering and UI, and the real-time
// factor, on the default tank-and-hand scene with a replayed interaction. Needs a display (xvfb-run -a works,
// llvmpipe).
//   fp_bench_app [--frames N] [--width W] [--height H] [--mode NAME] [--hand-script FILE] [--fixed-step]
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/desktop_platform.h"
#include "engine/headless_app.h"

using namespace fp::engine;

namespace {

struct Sample {
  double frame, simTask, wait, render, ui, capture, input, present, steps, rtf;
};

/// Wraps the window and takes each frame's figures once its steps have finished.
class Meter : public AppPlatform {
 public:
  explicit Meter(DesktopPlatform& w) : window(w) {}
  bool running() override { return window.running(); }
  FrameClock beginFrame() override { return window.beginFrame(); }
  void input(AppSession& session, const FrameClock& clock) override {
    if (frames++ > 0) {
      const SessionStats& s = session.stats();
      const FrameTiming& t = window.timing();
      samples.push_back({s.frameMs, s.simMs, s.waitMs, t.render, t.ui, t.capture, t.input, t.present,
                         double(s.steps), double(s.realTimeFactor.last())});
    }
    window.input(session, clock);
  }
  void capture(AppSession& session, int frame) override { window.capture(session, frame); }
  void draw(AppSession& session, int frame) override { window.draw(session, frame); }
  double stepBudget() const override { return window.stepBudget(); }
  DesktopPlatform& window;
  std::vector<Sample> samples;
  int frames = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int frames = 180;
  std::vector<std::string> args;
  std::string mode = "fluidplaying";
  std::string script = std::string(FP_SOURCE_DIR) + "/assets/hands/splash.csv";
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--frames" && k + 1 < argc) {
      frames = std::atoi(argv[++k]);
    } else if (a == "--mode" && k + 1 < argc) {
      mode = argv[++k];
    } else if (a == "--hand-script" && k + 1 < argc) {
      script = argv[++k];
    } else {
      args.push_back(a);
    }
  }
  std::vector<std::string> cli = {
      "--scene",       std::string(FP_SOURCE_DIR) + "/assets/scenes/hand_tank.json",
      "--mode",        mode,
      "--hand-script", script,
      "--frames",      std::to_string(frames)};
  cli.insert(cli.end(), args.begin(), args.end());
  CliOptions o;
  try {
    o = parseCommandLine(cli);
  } catch (const std::exception& e) {
    std::cerr << "fp_bench_app: " << e.what() << "\n";
    return 2;
  }
  try {
    DesktopPlatform window(o, o.frames);
    AppSession session(sessionConfigOf(o));
    Meter meter(window);
    // water
    runAppLoop(session, meter, o.frames);
    // the first frames build GL objects and the split templates: leave out the first 10
    const std::size_t skip = std::min<std::size_t>(10, meter.samples.size() / 4);
    Sample mean{};
    std::size_t n = 0;
    for (std::size_t k = skip; k < meter.samples.size(); ++k, ++n) {
      const Sample& s = meter.samples[k];
      mean.frame += s.frame;
      mean.simTask += s.simTask;
      mean.wait += s.wait;
      mean.render += s.render;
      mean.ui += s.ui;
      mean.capture += s.capture;
      mean.input += s.input;
      mean.present += s.present;
      mean.steps += s.steps;
    }
    const double d = n ? double(n) : 1.0;
    std::printf(
        "fp_bench_app: %s, %dx%d, scene hand_tank (%s), hand %s, %zu frames measured, %zu particles at "
        "the end, %s\n",
        window.contextDescription().c_str(), o.sizeGiven ? o.width : 1280, o.sizeGiven ? o.height : 720,
        mode.c_str(), script.substr(script.find_last_of('/') + 1).c_str(), n,
        session.simulation().particles().size(), o.fixedStep ? "fixed steps" : "real time");
    std::printf(
        "\n| frame ms | fps | steps/frame | sim ms (workers) | sim wait ms | render ms | UI ms | "
        "upload+spray ms "
        "| input ms | present ms | real-time factor |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::printf("| %.1f | %.1f | %.2f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.3f |\n",
                mean.frame / d, 1000.0 * d / std::max(mean.frame, 1e-9), mean.steps / d, mean.simTask / d,
                mean.wait / d, mean.render / d, mean.ui / d, mean.capture / d, mean.input / d,
                mean.present / d, session.meanRealTimeFactor());
    std::printf("\ncsv,frame_ms,steps,sim_ms,wait_ms,render_ms,ui_ms,capture_ms,input_ms,present_ms,rtf\n");
    std::printf("csv,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f\n", mean.frame / d, mean.steps / d,
                mean.simTask / d, mean.wait / d, mean.render / d, mean.ui / d, mean.capture / d,
                mean.input / d, mean.present / d, session.meanRealTimeFactor());
  } catch (const std::exception& e) {
    std::cerr << "fp_bench_app: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
