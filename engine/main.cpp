/// fluidplaying: the FluidPlaying executable. This build has the headless mode; the desktop window and the
/// OpenXR mode plug into the same loop later.

#include <iostream>
#include <stdexcept>

#include "engine/cli.h"
#include "engine/headless_runner.h"

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
    const RunSummary summary = runHeadless(options, std::cout, std::cerr);
    printSummary(std::cout, summary);
    if (!options.statsPath.empty())
      writeStatsJson(options.statsPath, summary);
    if (summary.status != "ok") {
      std::cerr << "fluidplaying: " << summary.message << "\n";
      return kExitUnstable;
    }
  } catch (const fp::sim::InputError& e) {
    std::cerr << "fluidplaying: " << e.what() << "\n";
    return kExitInput;
  }
  return kExitOk;
}
