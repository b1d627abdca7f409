#pragma once
/// Command line of the `fluidplaying` executable.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace fp::engine {

/// Exit codes of `fluidplaying`.
enum ExitCode : int {
  kExitOk = 0,
  kExitUsage = 2,     ///< bad command line
  kExitInput = 3,     ///< bad scene or asset, unwritable output
  kExitUnstable = 4,  ///< the simulation went unstable
};

/// Parsed command-line options.
struct CliOptions {
  bool help = false;                  ///< --help
  bool headless = false;              ///< --headless
  std::string scenePath;              ///< --scene FILE (default: the dam break)
  std::optional<int> frames;          ///< --frames N
  std::optional<double> simTime;      ///< --sim-time S
  int threads = 0;                    ///< --threads T (0: all cores)
  std::optional<std::uint64_t> seed;  ///< --seed N
  std::string statsPath;              ///< --stats FILE.json
  std::string exportDir;              ///< --export DIR
  bool quiet = false;                 ///< --quiet: no progress lines
  std::string mode;                   ///< --mode NAME (empty: the scene's mode)
  // rendering (headless, through OSMesa)
  bool render = false;                  ///< --render: write a PNG of every frame (implies --headless)
  std::string outDir;                   ///< --out DIR: folder of the PNG files
  int width = 1280;                     ///< --width W [px], in [16, 8192]
  int height = 720;                     ///< --height H [px], in [16, 8192]
  std::string view = "fluid";           ///< --view fluid | particles
  std::string colorField;               ///< --color FIELD of the particle view (implies --view particles)
  std::optional<double> highlightTime;  ///< --highlight-time S: red tint of split children [s], 0 = off
  bool noSpray = false;                 ///< --no-spray
  std::string shaderDir;                ///< --shaders DIR (default: shaders/ here, else the source tree's)
};

/// Parses argv; throws std::invalid_argument with a one-line message for bad input.
CliOptions parseCommandLine(const std::vector<std::string>& args);

/// The usage text.
std::string usage();

/// The default scene: assets/scenes/dam_break.json in the working directory, else in the source tree.
std::string defaultScenePath();

}  // namespace fp::engine
