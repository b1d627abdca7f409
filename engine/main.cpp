/// fluidplaying: the FluidPlaying executable. Without --headless it opens the desktop window (real-time
/// water, the mouse hand, the panel); with --headless it runs the scene through the same app loop in fixed
/// frame steps (with a recorded hand replayed when --hand-script is given). Without a display the window mode
/// says so in one line and runs headless instead.

#include <iostream>
#include <memory>
#include <stdexcept>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/cli_app.h"
#include "engine/desktop_platform.h"
#include "engine/headless_app.h"
#include "engine/headless_render.h"
#include "engine/headless_runner.h"
#include "engine/tracked_hands.h"
#include "render/render_error.h"
#ifdef FP_HAVE_XR
#include "engine/xr_app.h"
#include "engine/xr_program.h"
#endif

namespace {

using namespace fp::engine;

int runWindow(CliOptions options) {
  // the window and its shaders first: a missing shader stops the run before the scene is built
  DesktopPlatform platform(options, options.frames);
  // (not with --load-state: a saved state belongs to the scene it was saved from, the default one)
  if (options.sceneDefaulted && options.loadState.empty() && isSoftwareGl(platform.contextDescription())) {
    // the rasteriser draws on the simulation's cores: the r = 5 mm tank ran at 0.66 of real time there
    options.scenePath = softwareGlScenePath();
    if (!options.quiet) {
      std::cout << "software OpenGL: the coarse hand tank (r = 7.9 mm), nearer real time here; --scene "
                   "assets/scenes/hand_tank.json plays at r = 5 mm\n";
    }
  }
  const std::optional<JointReplay> joints = JointReplay::ofScript(options.handScript);
  AppSession session(sessionConfigOf(options));
  JointReplayPlatform replay(platform, joints, session, options.handScale);
  if (!options.quiet) {
    std::cout << "window " << platform.contextDescription() << "; scene " << session.scene().name << " ("
              << fp::sim::modeName(session.mode()) << "), " << session.simulation().particles().size()
              << " particles; F1 lists the controls\n";
  }
  const int frames = runAppLoop(session, replay, options.frames);
  platform.finish();
  if (!options.quiet) {
    std::cout << "frames " << frames << ", simulated " << session.simulation().time()
              << " s, real-time factor " << session.meanRealTimeFactor() << "\n";
  }
  if (!options.screenshot.empty() && !options.quiet)
    std::cout << "screenshot " << options.screenshot << "\n";
  return kExitOk;
}

int runHeadlessMode(const CliOptions& options) {
  // The context and the shaders come first, so a missing shader stops the run before any simulation.
  std::unique_ptr<HeadlessRender> render;
  FrameCallback onFrame;
  if (options.render) {
    render = std::make_unique<HeadlessRender>(options);
    if (!options.quiet) {
      std::cout << "rendering " << options.width << "x" << options.height << " " << options.view
                << " view into " << (options.outDir.empty() ? options.videoPath : options.outDir) << " ("
                << render->contextDescription() << ")\n";
    }
    onFrame = [&render](int frame, const fp::sim::Simulation& simulation,
                        const fp::sim::SplashParticles& splash) {
      render->renderFrame(frame, simulation, &splash);
    };
  }
  const RunSummary summary = runHeadless(options, std::cout, std::cerr, onFrame);
  printSummary(std::cout, summary);
  if (!options.handScript.empty())
    std::cout << "momentum             " << summary.momentumFinal.transpose() << " kg m/s\n";
  if (render) {
    render->finish();
    if (!options.videoPath.empty())
      std::cout << "video                " << options.videoPath << "\n";
    std::cout << "images               " << render->imagesWritten() << " (" << render->meanMilliseconds()
              << " ms each)\n";
  }
  if (!options.statsPath.empty())
    writeStatsJson(options.statsPath, summary);
  if (summary.status != "ok") {
    std::cerr << "fluidplaying: " << summary.message << "\n";
    return kExitUnstable;
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CliOptions options;
  try {
    options = parseCommandLine(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const std::invalid_argument& e) {
    std::cerr << usageErrorLine("fluidplaying", e.what()) << "\n";
    return kExitUsage;
  }
  if (options.help) {
    std::cout << usage();
    return kExitOk;
  }
  const ThreadLimit threads(options.threads);  // one limit for the window and the headless modes
  try {
    if (options.xr || options.xrRequired) {
#ifdef FP_HAVE_XR
      try {
        return runXrApp(options, std::cout);
      } catch (const XrUnavailable& e) {
        if (options.xrRequired) {
          std::cerr << "fluidplaying: " << e.what() << " (--xr-required)\n";
          return kExitNoHeadset;
        }
        std::cerr << "fluidplaying: " << e.what() << "; playing on the desktop instead\n";
      }
#else
      if (options.xrRequired) {
        std::cerr << "fluidplaying: built without OpenXR (--xr-required)\n";
        return kExitNoHeadset;
      }
      std::cerr << "fluidplaying: built without OpenXR; playing on the desktop instead\n";
#endif
    }
    if (!options.headless) {
      try {
        return runWindow(options);
      } catch (const WindowUnavailable& e) {
        // the documented fallback: the same scene (and hand script) headless, so scripts still get a result
        std::cerr << "fluidplaying: " << e.what()
                  << "; running headless instead (--headless skips the window)\n";
        options.headless = true;
      }
    }
    return runHeadlessMode(options);
  } catch (const std::invalid_argument& e) {
    // a --set that breaks a relation with the scene's own parameters (dt_min above its dt_max)
    std::cerr << usageErrorLine("fluidplaying", e.what()) << "\n";
    return kExitUsage;
  } catch (const fp::sim::InputError& e) {
    std::cerr << "fluidplaying: " << e.what() << "\n";
    return kExitInput;
  } catch (const fp::render::RenderError& e) {
    std::cerr << "fluidplaying: " << e.what() << "\n";
    return kExitInput;
  }
}
