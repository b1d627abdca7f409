#include "engine/cli.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "engine/cli_app.h"
#include "render/fluid_renderer.h"
#include "render/particle_colors.h"
#include "render/render_settings.h"
#include "sim/params.h"
#include "sim/scene.h"

namespace fp::engine {

double parseNumber(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || !std::isfinite(value)) {
    throw std::invalid_argument(flag + " expects a number, got '" + text + "'");
  }
  return value;
}

long long parseInteger(const std::string& flag, const std::string& text, long long min, long long max) {
  const double value = parseNumber(flag, text);
  if (value != std::floor(value) || value < double(min) || value > double(max)) {
    throw std::invalid_argument(flag + " expects an integer in [" + std::to_string(min) + ", " +
                                std::to_string(max) + "], got '" + text + "'");
  }
  return (long long)value;
}

double parsePositive(const std::string& flag, const std::string& text) {
  const double value = parseNumber(flag, text);
  if (!(value > 0.0))
    throw std::invalid_argument(flag + " expects a positive number, got '" + text + "'");
  return value;
}

namespace {

// a Choice entry of the render settings' table, checked against its names
CLI::Validator tableChoice(const std::string& key) {
  const std::vector<std::string>& names = render::RenderSettingsTable::get().at(key).choices;
  std::string list;
  for (std::size_t k = 0; k < names.size(); ++k)
    list += (k ? k + 1 == names.size() ? " or " : ", " : "") + names[k];
  return choiceOf(list, [&names](const std::string& v) {
    return std::find(names.begin(), names.end(), v) != names.end();
  });
}

// The declaration of fluidplaying's command line: every option once, with its type, range and help. Checks
// that depend on the mode (window, headless, --render) follow the parse.
struct Declaration {
  CommandLine line{
      "fluidplaying",
      "fluidplaying: real-time adaptive SPH water. Without --headless it opens the window (water, "
      "mouse hand, panel; F1 lists the controls); without a display it says so in one line and "
      "runs headless instead. --headless runs a scene without a window, or the app loop in "
      "fixed frame steps when a recorded hand is replayed (--hand-script)."};
  CLI::Option* frames = nullptr;
  CLI::Option* simTime = nullptr;
  CLI::Option* render = nullptr;
  CLI::Option* out = nullptr;
  CLI::Option* view = nullptr;
  CLI::Option* color = nullptr;
  std::vector<CLI::Option*> viewOnly;    // options of a view: --render or the window
  std::vector<CLI::Option*> windowOnly;  // options of the window

  explicit Declaration(CliOptions& o) {
    CLI::App& app = line.app();
    const std::string run = "Run", app_ = "App (window, and the headless hand replay)", view_ = "View",
                      window = "Window", headless = "Headless";
    app.get_help_ptr()->group(run);
    app.add_flag("--headless", o.headless, "run without a window")->group(run);
    app.add_option(
           "--scene", o.scenePath,
           "scene JSON (default assets/scenes/hand_tank.json in the window, hand_tank_coarse.json there "
           "on software OpenGL, dam_break.json headless)")
        ->type_name("FILE")
        ->group(run);
    app.add_option("--mode", o.mode,
                   "resolution mode: " + std::string(sim::modeNames()) + " (default: the scene's)")
        ->type_name("NAME")
        ->check(choiceOf(sim::modeNames(), [](const std::string& m) { return bool(sim::parseMode(m)); }))
        ->group(run);
    frames = line.addInteger(
                     "--frames", [&o](long long n) { o.frames = int(n); }, 1, 100000000,
                     "headless: simulate N frames at the scene's frame rate; window: quit after N frames")
                 ->group(run);
    simTime = line.addPositive(
                      "--sim-time", [&o](double s) { o.simTime = s; },
                      "headless: simulate S seconds (default: the scene's sim_time)")
                  ->group(run)
                  ->excludes(frames);
    line.addInteger(
            "--threads", [&o](long long n) { o.threads = int(n); }, 1, 1024,
            "worker threads (default: all cores)")
        ->group(run);
    line.addSeed([&o](std::uint64_t s) { o.seed = s; })->group(run);
    line.addSet(o.sets)->group(run);
    app.add_flag("--quiet", o.quiet, "no progress lines")->group(run);
    app.add_option("--load-state", o.loadState,
                   "start from a state saved by --save-state (same scene, --mode, --seed, --set of non-live "
                   "parameters and hand size); --frames and --sim-time then count from it")
        ->type_name("FILE")
        ->group(run);
    CLI::Option* save =
        app.add_option("--save-state", o.saveState,
                       "write the state at the end of the run (and every --save-state-every frames); the "
                       "window's panel resets to it")
            ->type_name("FILE")
            ->group(run);
    line.addInteger(
            "--save-state-every", [&o](long long n) { o.saveStateEvery = int(n); }, 1, 100000000,
            "with --save-state: also write it every N frames (each time over the last)")
        ->group(run)
        ->needs(save);

    app.add_option(
           "--hand-script", o.handScript,
           "replay a recorded hand (assets/hands/*.csv) from time 0; headless it runs the app loop in "
           "fixed frame steps")
        ->type_name("FILE")
        ->group(app_);
    line.addNumber(
            "--hand-size", [&o](double s) { o.handScale = s; }, 0.5, 3.0,
            "hand scale factor (default 1: an adult hand)")
        ->group(app_);

    windowOnly.push_back(app.add_flag("--fixed-step", o.fixedStep,
                                      "every frame advances 1/frame_rate of simulated time, however long it "
                                      "takes (videos, tests); default: real time, slowed when the machine "
                                      "cannot keep up")
                             ->group(window));
    windowOnly.push_back(line.addNumber(
                                 "--time-scale", [&o](double s) { o.timeScale = s; }, 0.05, 4.0,
                                 "simulated seconds per wall second (default 1)")
                             ->group(window));
    windowOnly.push_back(
        app.add_option("--screenshot", o.screenshot, "write the last frame, panel included, as PNG")
            ->type_name("FILE.png")
            ->group(window));
    windowOnly.push_back(
        app.add_option("--record-frames", o.recordDir, "write every frame's view as DIR/frame_NNNNN.png")
            ->type_name("DIR")
            ->group(window));
    windowOnly.push_back(
        app.add_flag("--fullscreen", o.fullscreen, "start full screen (F11 toggles)")->group(window));
    windowOnly.push_back(
        app.add_flag("--no-panel", o.noPanel, "start with the panel hidden (Tab toggles)")->group(window));

    app.add_flag(
           "--xr", o.xr,
           "play in an OpenXR headset (docs/xr.md); without a runtime, headset or GL support it says so in "
           "one line and opens the window instead")
        ->group(app_);
    app.add_flag("--xr-required", o.xrRequired,
                 "like --xr, but exit with code 5 when the headset cannot be used")
        ->group(app_);
    app.add_flag("--no-window", o.noWindow, "with --xr: no mirror window")->group(app_);
    app.add_option("--record-hands", o.recordHands, "with --xr: record the tracked hands as a joint CSV")
        ->type_name("FILE")
        ->group(app_);
    app.add_option_function<std::string>(
           "--debug-slow-steps",
           [&o](const std::string& text) {
             const std::size_t comma = text.find(',');
             if (comma == std::string::npos)
               throw std::invalid_argument("--debug-slow-steps expects N,MS, got '" + text + "'");
             o.slowSteps = int(parseInteger("--debug-slow-steps", text.substr(0, comma), 0, 1000000));
             o.slowStepMs = parseNumber("--debug-slow-steps", text.substr(comma + 1));
             if (o.slowStepMs < 0.0 || o.slowStepMs > 10000.0)
               throw std::invalid_argument("--debug-slow-steps: MS in [0, 10000], got '" + text + "'");
           },
           "a solver slower than the display (tests): the first N solver steps each take MS ms longer")
        ->type_name("N,MS")
        ->group(app_);

    app.add_option("--stats", o.statsPath, "write the run's statistics as JSON")
        ->type_name("FILE.json")
        ->group(headless);
    app.add_option("--export", o.exportDir, "write the particles of every frame as binary PLY into DIR")
        ->type_name("DIR")
        ->group(headless);
    render = app.add_flag("--render", o.render,
                          "render every frame (frame 0 is the initial state) offscreen through OSMesa, no "
                          "display needed, and write DIR/frame_NNNNN.png; implies --headless")
                 ->group(headless);
    out = app.add_option("--out", o.outDir, "folder of the images (required with --render)")
              ->type_name("DIR")
              ->group(headless)
              ->needs(render);
    app.add_option("--video", o.videoPath,
                   "also write the rendered frames as a video at the scene's frame rate, through the ffmpeg "
                   "program")
        ->type_name("FILE.mp4")
        ->group(headless)
        ->needs(render);

    for (const char* side : {"--width", "--height"}) {
      int& target = std::string(side) == "--width" ? o.width : o.height;
      viewOnly.push_back(line.addInteger(
                                 side,
                                 [&o, &target](long long n) {
                                   target = int(n);
                                   o.sizeGiven = true;
                                 },
                                 16, 8192,
                                 std::string("image or window ") + (side[2] == 'w' ? "width" : "height") +
                                     " in pixels (default " + (side[2] == 'w' ? "1280" : "720") + ")")
                             ->group(view_));
    }
    view = app.add_option("--view", o.view,
                          "fluid (screen-space water, default) or particles (spheres coloured by --color); "
                          "--set view=NAME")
               ->type_name("NAME")
               ->check(tableChoice("view"))
               ->group(view_);
    viewOnly.push_back(view);
    color = app.add_option("--color", o.colorField,
                           "particle view colour: " + std::string(render::colorFieldNames()) +
                               " (default nu); implies --view particles; --set color_field=FIELD")
                ->type_name("FIELD")
                ->check(tableChoice("color_field"))
                ->group(view_);
    viewOnly.push_back(color);
    viewOnly.push_back(
        line.addNumber(
                "--highlight-time", [&o](double s) { o.highlightTime = s; }, 0.0,
                render::RenderSettingsTable::get().at("highlight_duration").max,
                "tint split children red for S seconds after their split (default 0.5; 0: off); --set "
                "highlight_duration=S")
            ->group(view_));
    viewOnly.push_back(
        app.add_flag("--no-spray", o.noSpray, "do not draw splash particles; --set show_spray=false")
            ->group(view_));
    viewOnly.push_back(app.add_option("--shaders", o.shaderDir,
                                      "GLSL folder (default: shaders/ here, else the source tree's)")
                           ->type_name("DIR")
                           ->group(view_));
    app.footer(
        "Exit codes: 0 ok, 2 bad command line, 3 bad scene, hand script, saved state, output or shader, 4 "
        "simulation unstable (headless; the window and the headset roll back to a good state instead).");
  }
};

}  // namespace

std::string usage() {
  CliOptions o;
  return Declaration(o).line.help();
}

CliOptions parseCommandLine(const std::vector<std::string>& args) {
  CliOptions o;
  Declaration d(o);
  if (!d.line.parse(args)) {
    o.help = true;
    return o;
  }
  if (o.render)
    o.headless = true;
  // --set names a simulation parameter or a render setting: each goes to its own table
  std::vector<std::string> sets;
  for (const std::string& kv : o.sets)
    (isRenderSetting(kv) ? o.renderSets : sets).push_back(kv);
  o.sets = std::move(sets);
  if (!o.renderSets.empty() && o.headless && !o.render)
    throw std::invalid_argument("--set " + o.renderSets.front() +
                                ": a render setting needs --render (or the window, without --headless)");
  auto firstGiven = [](const std::vector<CLI::Option*>& options) -> const CLI::Option* {
    for (const CLI::Option* option : options)
      if (option->count() > 0)
        return option;
    return nullptr;
  };
  if (const CLI::Option* v = firstGiven(d.viewOnly); v && o.headless && !o.render)
    throw std::invalid_argument(v->get_name() + " needs --render (or the window, without --headless)");
  if (const CLI::Option* w = firstGiven(d.windowOnly); w && o.headless)
    throw std::invalid_argument(w->get_name() + " applies to the window, not --headless");
  if (!o.headless && o.simTime)
    throw std::invalid_argument("--sim-time needs --headless (the window runs until closed or --frames)");
  if (o.render && o.outDir.empty() && o.videoPath.empty())
    throw std::invalid_argument("--render needs --out DIR or --video FILE.mp4");
  if (d.color->count() > 0) {
    if (d.view->count() > 0 && o.view == "fluid")
      throw std::invalid_argument("--color applies to --view particles, not --view fluid");
    o.view = "particles";
  }
  if (o.scenePath.empty()) {
    o.scenePath = o.headless ? defaultScenePath() : defaultAppScenePath();
    o.sceneDefaulted = true;
  }
  return o;
}

std::string applySetting(sim::SimParams& params, const std::string& keyValue) {
  return sim::ParamTable::sim().assign(params, keyValue);
}

bool isRenderSetting(const std::string& keyValue) {
  const std::string key = keyValue.substr(0, keyValue.find('='));
  return !sim::ParamTable::sim().find(key) && render::RenderSettingsTable::get().find(key);
}

std::string checkSetting(const std::string& keyValue) {
  if (isRenderSetting(keyValue)) {
    render::RenderSettings scratch;
    return render::RenderSettingsTable::get().assign(scratch, keyValue);
  }
  sim::SimParams scratch;
  std::string error = sim::ParamTable::sim().assign(scratch, keyValue);
  const std::size_t eq = keyValue.find('=');
  if (!error.empty() && eq != std::string::npos && eq > 0 &&
      !sim::ParamTable::sim().find(keyValue.substr(0, eq))) {
    // neither table knows the key: suggest the closest of either
    const std::string render = render::RenderSettingsTable::get().unknownKey(keyValue.substr(0, eq));
    if (error.find("did you mean") == std::string::npos && render.find("did you mean") != std::string::npos)
      error = render;
  }
  return error;
}

void applySettings(sim::SimParams& params, const std::vector<std::string>& keyValues) {
  if (keyValues.empty())
    return;
  const std::string error = sim::ParamTable::sim().assignAll(params, keyValues);
  if (!error.empty())
    throw std::invalid_argument("--set: " + error);
}

void overrideScene(sim::SceneDesc& scene, const SceneOverrides& overrides) {
  if (!overrides.mode.empty()) {
    const auto mode = sim::parseMode(overrides.mode);
    if (!mode) {
      throw std::invalid_argument("--mode expects one of " + std::string(sim::modeNames()) + ", got '" +
                                  overrides.mode + "'");
    }
    scene.mode = *mode;
  }
  if (overrides.seed)
    scene.params.seed = *overrides.seed;
  applySettings(scene.params, overrides.sets);
}

void applyRenderOptions(const CliOptions& options, render::RenderSettings& settings) {
  std::vector<std::string> sets;
  if (options.view != "fluid")
    sets.push_back("view=" + options.view);
  if (!options.colorField.empty())
    sets.push_back("color_field=" + options.colorField);
  if (options.highlightTime) {
    sets.push_back(*options.highlightTime > 0.0 ? "highlight_splits=true" : "highlight_splits=false");
    if (*options.highlightTime > 0.0) {
      std::ostringstream duration;
      duration << std::setprecision(17) << *options.highlightTime;
      sets.push_back("highlight_duration=" + duration.str());
    }
  }
  if (options.noSpray)
    sets.push_back("show_spray=false");
  sets.insert(sets.end(), options.renderSets.begin(), options.renderSets.end());
  const std::string error = render::RenderSettingsTable::get().assignAll(settings, sets);
  if (!error.empty())
    throw std::invalid_argument("--set: " + error);
}

struct ThreadLimit::Control {
  explicit Control(int count) : control(tbb::global_control::max_allowed_parallelism, std::size_t(count)) {}
  tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads)
    : m_count(threads > 0 ? threads : int(tbb::info::default_concurrency())),
      m_control(std::make_unique<Control>(m_count)) {}

ThreadLimit::~ThreadLimit() = default;

std::string assetPath(const std::string& relative) {
  if (std::filesystem::exists(relative))
    return relative;
  return std::string(FP_SOURCE_DIR) + "/" + relative;
}

std::string defaultAppScenePath() {
  return assetPath("assets/scenes/hand_tank.json");
}

std::string softwareGlScenePath() {
  return assetPath("assets/scenes/hand_tank_coarse.json");
}

bool isSoftwareGl(const std::string& contextDescription) {
  for (const char* name :
       {"llvmpipe", "softpipe", "swrast", "Software Rasterizer", "Software Renderer", "GDI Generic"}) {
    if (contextDescription.find(name) != std::string::npos)
      return true;
  }
  return false;
}

std::string defaultScenePath() {
  return assetPath("assets/scenes/dam_break.json");
}

}  // namespace fp::engine
