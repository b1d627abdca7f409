/// fluidplaying: the FluidPlaying executable. This build has the headless mode, which can also render every
/// frame offscreen (OSMesa) to PNG; the desktop window and the OpenXR mode plug into the same loop later.

#include <iostream>
#include <memory>
#include <stdexcept>

#include "engine/cli.h"
#include "engine/headless_render.h"
#include "engine/headless_runner.h"
#include "render/render_error.h"

int main(int argc, char** argv) {
  using namespace fp::engine;
  CliOptions options;
  try {
    options = parseCommandLine(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const std::invalid_argument& e) {
    std::cerr << "fluidplaying: " << e.what() << "\n" << usage();
    return kExitUsage;
  }
  if (options.help) {
    std::cout << usage();
    return kExitOk;
  }
  if (!options.headless) {
    std::cerr << "fluidplaying: no window mode in this build yet; running headless\n";
  }
  try {
    // The context and the shaders come first, so a missing shader stops the run before any simulation.
    std::unique_ptr<HeadlessRender> render;
    FrameCallback onFrame;
    if (options.render) {
      render = std::make_unique<HeadlessRender>(options);
      if (!options.quiet) {
        std::cout << "rendering " << options.width << "x" << options.height << " " << options.view
                  << " view into " << options.outDir << " (" << render->contextDescription() << ")\n";
      }
      onFrame = [&render](int frame, const fp::sim::Simulation& simulation) {
        render->renderFrame(frame, simulation);
      };
    }
    const RunSummary summary = runHeadless(options, std::cout, std::cerr, onFrame);
    printSummary(std::cout, summary);
    if (render) {
      std::cout << "images               " << render->imagesWritten() << " (" << render->meanMilliseconds()
                << " ms each)\n";
    }
    if (!options.statsPath.empty())
      writeStatsJson(options.statsPath, summary);
    if (summary.status != "ok") {
      std::cerr << "fluidplaying: " << summary.message << "\n";
      return kExitUnstable;
    }
  } catch (const fp::sim::InputError& e) {
    std::cerr << "fluidplaying: " << e.what() << "\n";
    return kExitInput;
  } catch (const fp::render::RenderError& e) {
    std::cerr << "fluidplaying: " << e.what() << "\n";
    return kExitInput;
  }
  return kExitOk;
}
