// fp_bench_app: the desktop app's frame time split into simulation, rendering and UI, and the real-time
// factor, on the default tank-and-hand scene with a replayed interaction. Needs a display (xvfb-run -a works,
// llvmpipe).
//   fp_bench_app [--frames N] [--width W] [--height H] [--mode NAME] [--hand-script FILE] [--fixed-step]
//                [--set KEY=VALUE]... [--help]
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/cli_app.h"
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
  CliOptions o;
  o.scenePath = std::string(FP_SOURCE_DIR) + "/assets/scenes/hand_tank.json";
  o.mode = "fluidplaying";
  o.handScript = std::string(FP_SOURCE_DIR) + "/assets/hands/splash.csv";
  o.frames = 180;
  CommandLine line(
      "fp_bench_app",
      "fp_bench_app: the desktop app's frame time split into simulation, rendering and UI, and "
      "the real-time factor, on the hand tank with a replayed hand. Needs a display (xvfb-run -a).");
  line.addInteger(
      "--frames", [&o](long long n) { o.frames = int(n); }, 1, 1000000, "frames to run (default 180)");
  for (const char* side : {"--width", "--height"}) {
    int& target = side[2] == 'w' ? o.width : o.height;
    line.addInteger(
        side,
        [&o, &target](long long n) {
          target = int(n);
          o.sizeGiven = true;
        },
        16, 8192,
        std::string("window ") + (side[2] == 'w' ? "width (default 1280)" : "height (default 720)"));
  }
  line.app()
      .add_option("--mode", o.mode, "resolution mode (default fluidplaying)")
      ->type_name("NAME")
      ->check(
          choiceOf(fp::sim::modeNames(), [](const std::string& m) { return bool(fp::sim::parseMode(m)); }));
  line.app()
      .add_option("--hand-script", o.handScript, "the replayed hand (default assets/hands/splash.csv)")
      ->type_name("FILE");
  line.app().add_flag("--fixed-step", o.fixedStep, "every frame advances 1/frame_rate (default: real time)");
  line.addSet(o.sets);
  if (const std::optional<int> exit = line.parse(argc, argv))
    return *exit;
  for (auto it = o.sets.begin(); it != o.sets.end();) {  // render settings go to the renderer
    if (isRenderSetting(*it)) {
      o.renderSets.push_back(*it);
      it = o.sets.erase(it);
    } else {
      ++it;
    }
  }
  const std::string mode = o.mode;
  const std::string script = o.handScript;
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
  } catch (const std::invalid_argument& e) {  // a --set that breaks a relation with the scene's values
    std::cerr << usageErrorLine("fp_bench_app", e.what()) << "\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "fp_bench_app: " << e.what() << "\n";
    return kExitInput;
  }
  return 0;
}
