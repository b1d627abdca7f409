#pragma once
/// Command line of the `fluidplaying` executable.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace fp::sim {
struct SceneDesc;
struct SimParams;
}  // namespace fp::sim
namespace fp::render {
struct RenderSettings;
}

namespace fp::engine {

/// Exit codes of `fluidplaying`.
enum ExitCode : int {
  kExitOk = 0,
  kExitUsage = 2,      ///< bad command line
  kExitInput = 3,      ///< bad scene or asset, unwritable output
  kExitUnstable = 4,   ///< the simulation went unstable
  kExitNoHeadset = 5,  ///< --xr-required and no OpenXR runtime, headset or GL support
};

/// Parsed command-line options.
struct CliOptions {
  bool help = false;              ///< --help
  bool headless = false;          ///< --headless
  std::string scenePath;          ///< --scene FILE (default: the hand tank in the window, else the dam break)
  bool sceneDefaulted = false;    ///< no --scene was given: scenePath is the default of the mode
  std::optional<int> frames;      ///< --frames N
  std::optional<double> simTime;  ///< --sim-time S
  int threads = 0;                ///< --threads T (0: all cores)
  std::optional<std::uint64_t> seed;    ///< --seed N, in the table's range of `seed`
  std::vector<std::string> sets;        ///< --set KEY=VALUE of simulation parameters, over the scene's
  std::vector<std::string> renderSets;  ///< --set KEY=VALUE of render settings (render/render_settings)
  std::string statsPath;                ///< --stats FILE.json
  std::string exportDir;                ///< --export DIR
  bool quiet = false;                   ///< --quiet: no progress lines
  std::string mode;                     ///< --mode NAME (empty: the scene's mode)
  std::string loadState;                ///< --load-state FILE: start from a saved state
  std::string saveState;                ///< --save-state FILE: the state at the end (and every N frames)
  int saveStateEvery = 0;               ///< --save-state-every N frames (0: only at the end)
  // rendering (headless, through OSMesa)
  bool render = false;                  ///< --render: write a PNG of every frame (implies --headless)
  std::string outDir;                   ///< --out DIR: folder of the PNG files
  std::string videoPath;                ///< --video FILE.mp4: the rendered frames as a video (ffmpeg)
  int width = 1280;                     ///< --width W [px], in [16, 8192]
  int height = 720;                     ///< --height H [px], in [16, 8192]
  std::string view = "fluid";           ///< --view fluid | particles
  std::string colorField;               ///< --color FIELD of the particle view (implies --view particles)
  std::optional<double> highlightTime;  ///< --highlight-time S: red tint of split children [s], 0 = off
  bool noSpray = false;                 ///< --no-spray
  std::string shaderDir;                ///< --shaders DIR (default: shaders/ here, else the source tree's)
  // the app (window, and the headless hand replay)
  std::string handScript;   ///< --hand-script FILE: replay a recorded hand (pose-track CSV)
  double handScale = 1.0;   ///< --hand-size S: hand scale factor, in [0.5, 3]
  bool fixedStep = false;   ///< --fixed-step: every frame advances 1 / frame_rate of simulated time
  double timeScale = 1.0;   ///< --time-scale S: simulated seconds per wall second, in [0.05, 4]
  std::string screenshot;   ///< --screenshot FILE.png: the last frame, panel included (window)
  std::string recordDir;    ///< --record-frames DIR: every frame's view as PNG (window)
  bool fullscreen = false;  ///< --fullscreen (window)
  bool noPanel = false;     ///< --no-panel: start with the panel hidden (window)
  bool sizeGiven = false;   ///< --width or --height was given
  // the headset (OpenXR)
  bool xr = false;          ///< --xr: play in an OpenXR headset
  bool xrRequired = false;  ///< --xr-required: like --xr, exit with kExitNoHeadset when it cannot be used
  bool noWindow = false;    ///< --no-window: no mirror window in the headset mode
  std::string recordHands;  ///< --record-hands FILE: the tracked hands as a joint CSV
  int slowSteps = 0;        ///< --debug-slow-steps N,MS: the first N solver steps ...
  double slowStepMs = 0.0;  ///< ... each take MS ms longer (a solver slower than the display, for tests)
};

/// A finite number, the whole of `text`; throws std::invalid_argument naming `flag` otherwise.
double parseNumber(const std::string& flag, const std::string& text);
/// An integer in [min, max], the whole of `text`; throws std::invalid_argument naming `flag` otherwise.
long long parseInteger(const std::string& flag, const std::string& text, long long min, long long max);
/// A finite number > 0, the whole of `text`; throws std::invalid_argument naming `flag` otherwise.
double parsePositive(const std::string& flag, const std::string& text);

/// Parses the arguments (without the program name) with the CLI11 declaration of `fluidplaying`; throws
/// std::invalid_argument with a one-line message for bad input. --help sets `help`.
CliOptions parseCommandLine(const std::vector<std::string>& args);

/// The --help text of `fluidplaying`.
std::string usage();

/// Applies one "KEY=VALUE" to `params`: "" or the table's one-line error (unknown key, type, range).
/// Relations between parameters are checked by applySettings.
std::string applySetting(sim::SimParams& params, const std::string& keyValue);
/// Checks one "KEY=VALUE" of --set against the simulation's table, else the render settings' table: "" or
/// the table's one-line error (an unknown key names the closest key of either table).
std::string checkSetting(const std::string& keyValue);
/// whether "KEY=VALUE" names a render setting (render::RenderSettingsTable) rather than a parameter
bool isRenderSetting(const std::string& keyValue);
/// Applies "KEY=VALUE" settings in order, then checks the relations between parameters; throws
/// std::invalid_argument "--set ...: why" (a bad command line).
void applySettings(sim::SimParams& params, const std::vector<std::string>& keyValues);

/// What the command line changes in a scene: the resolution mode, the seed and --set settings.
struct SceneOverrides {
  std::string mode;                   ///< mode name (empty: the scene's)
  std::optional<std::uint64_t> seed;  ///< seed (none: the scene's)
  std::vector<std::string> sets;      ///< "KEY=VALUE" settings, in order
};
/// Applies the overrides to a loaded scene; throws std::invalid_argument for a bad mode or setting.
void overrideScene(sim::SceneDesc& scene, const SceneOverrides& overrides);

/// Sets what the options ask of the renderer in `settings`, through the render settings' table: the aliases
/// --view, --color, --highlight-time and --no-spray, then the render settings of --set in order. Throws
/// std::invalid_argument for a setting the table refuses.
void applyRenderOptions(const CliOptions& options, render::RenderSettings& settings);

/// The thread limit of a run: `threads` workers (0: all cores) for as long as it lives.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;
  /// the number of workers allowed
  int count() const { return m_count; }

 private:
  int m_count;
  struct Control;
  std::unique_ptr<Control> m_control;
};

/// The default scene of the headless mode: assets/scenes/dam_break.json in the working directory, else in the
/// source tree.
std::string defaultScenePath();
/// The default scene of the window: assets/scenes/hand_tank.json (r = 5 mm), found like defaultScenePath().
std::string defaultAppScenePath();
/// The window's default where it draws with software OpenGL: assets/scenes/hand_tank_coarse.json
/// (r = 7.9 mm), which keeps the frame rate and the simulation near real time with the rasteriser on the
/// simulation's cores.
std::string softwareGlScenePath();
/// Whether an OpenGL context description ("version, renderer", as the window reports it) names a software
/// rasteriser: Mesa's llvmpipe, softpipe or swrast, Apple's or Microsoft's software renderer.
bool isSoftwareGl(const std::string& contextDescription);
/// An asset path relative to the repository (e.g. "assets/hands/push.csv"): here, else in the source tree.
std::string assetPath(const std::string& relative);

}  // namespace fp::engine
