#include "engine/cli.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "render/particle_colors.h"
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

std::string usage() {
  return "usage: fluidplaying [--scene FILE] [--mode NAME] [--hand-script FILE] [--frames N] [--screenshot "
         "FILE.png]\n"
         "                    [--record-frames DIR] [--fixed-step] [--time-scale S] [--hand-size S] "
         "[--fullscreen]\n"
         "                    [--no-panel] [--width W] [--height H] [--threads T] [--seed N] [view options]\n"
         "       fluidplaying --headless [--scene FILE] [--frames N | --sim-time S] [--threads T] [--seed "
         "N]\n"
         "                    [--mode NAME] [--hand-script FILE] [--stats FILE.json] [--export DIR] "
         "[--quiet]\n"
         "                    [--render --out DIR [--width W] [--height H] [view options]]\n"
         "  view options: [--view fluid|particles] [--color FIELD] [--highlight-time S] [--no-spray] "
         "[--shaders "
         "DIR]\n"
         "  (no --headless)  open the window: real-time water, mouse hand, panel (F1: controls); without a\n"
         "                  display it says so in one line and runs headless instead\n"
         "  --headless      run without a window\n"
         "  --scene FILE    scene JSON (default assets/scenes/hand_tank.json in the window, dam_break.json\n"
         "                  headless)\n"
         "  --frames N      headless: simulate N frames at the scene's frame rate; window: quit after N "
         "frames\n"
         "  --sim-time S    simulate S seconds (default: the scene's sim_time; headless)\n"
         "  --threads T     worker threads (default: all cores)\n"
         "  --seed N        seed of every random choice (overrides the scene)\n"
         "  --mode NAME     resolution: uniform-low, uniform-high, surface or fluidplaying (default: the "
         "scene's)\n"
         "  --hand-script FILE  replay a recorded hand (assets/hands/*.csv) from time 0; headless it runs "
         "the\n"
         "                  app loop in fixed frame steps\n"
         "  --hand-size S   hand scale factor in [0.5, 3] (default 1: an adult hand)\n"
         "  --fixed-step    window: every frame advances 1/frame_rate of simulated time, however long it "
         "takes\n"
         "                  (videos, tests); default: real time, slowed when the machine cannot keep up\n"
         "  --time-scale S  window: simulated seconds per wall second, in [0.05, 4] (default 1)\n"
         "  --screenshot FILE  window: write the last frame, panel included, as PNG\n"
         "  --record-frames DIR  window: write every frame's view as DIR/frame_NNNNN.png\n"
         "  --fullscreen    window: start full screen (F11 toggles)\n"
         "  --no-panel      window: start with the panel hidden (Tab toggles)\n"
         "  --stats FILE    write the run's statistics as JSON (headless)\n"
         "  --export DIR    write the particles of every frame as binary PLY into DIR (headless)\n"
         "  --quiet         no progress lines\n"
         "  --render        render every frame (frame 0 is the initial state) offscreen through OSMesa, no\n"
         "                  display needed, and write DIR/frame_NNNNN.png; implies --headless\n"
         "  --out DIR       folder of the images (required with --render)\n"
         "  --width W       image or window width in pixels (default 1280)\n"
         "  --height H      image or window height in pixels (default 720)\n"
         "  --view NAME     fluid (screen-space water, default) or particles (spheres coloured by --color)\n"
         "  --color FIELD   particle view colour: mass, phi, omega, nu, speed or density-error (default nu)\n"
         "  --highlight-time S  tint split children red for S seconds after their split (default 0.5; 0: "
         "off)\n"
         "  --no-spray      do not draw splash particles\n"
         "  --shaders DIR   GLSL folder (default: shaders/ here, else the source tree's)\n"
         "exit codes: 0 ok, 2 bad command line, 3 bad scene, hand script, output or shader, 4 simulation "
         "unstable\n";
}

CliOptions parseCommandLine(const std::vector<std::string>& args) {
  CliOptions o;
  std::vector<std::string> renderOnly;  // options that mean nothing without --render
  std::vector<std::string> viewOnly;    // options of a view: --render or the window
  std::vector<std::string> windowOnly;  // options of the window
  bool colorGiven = false;
  bool viewGiven = false;
  for (std::size_t k = 0; k < args.size(); ++k) {
    const std::string& a = args[k];
    auto value = [&]() -> const std::string& {
      if (k + 1 >= args.size())
        throw std::invalid_argument(a + " needs a value");
      return args[++k];
    };
    if (a == "--help" || a == "-h") {
      o.help = true;
    } else if (a == "--headless") {
      o.headless = true;
    } else if (a == "--quiet") {
      o.quiet = true;
    } else if (a == "--scene") {
      o.scenePath = value();
    } else if (a == "--frames") {
      o.frames = int(parseInteger(a, value(), 1, 100000000));
    } else if (a == "--sim-time") {
      const double s = parseNumber(a, value());
      if (s <= 0.0)
        throw std::invalid_argument("--sim-time must be positive");
      o.simTime = s;
    } else if (a == "--threads") {
      o.threads = int(parseInteger(a, value(), 1, 1024));
    } else if (a == "--seed") {
      o.seed = std::uint64_t(parseInteger(a, value(), 0, 4294967295LL));
    } else if (a == "--stats") {
      o.statsPath = value();
    } else if (a == "--mode") {
      o.mode = value();
      if (!sim::parseMode(o.mode)) {
        throw std::invalid_argument("--mode expects one of " + std::string(sim::modeNames()) + ", got '" +
                                    o.mode + "'");
      }
    } else if (a == "--export") {
      o.exportDir = value();
    } else if (a == "--render") {
      o.render = true;
      o.headless = true;
    } else if (a == "--out") {
      o.outDir = value();
      renderOnly.push_back(a);
    } else if (a == "--width" || a == "--height") {
      (a == "--width" ? o.width : o.height) = int(parseInteger(a, value(), 16, 8192));
      o.sizeGiven = true;
      viewOnly.push_back(a);
    } else if (a == "--view") {
      o.view = value();
      if (o.view != "fluid" && o.view != "particles")
        throw std::invalid_argument("--view expects fluid or particles, got '" + o.view + "'");
      viewGiven = true;
      viewOnly.push_back(a);
    } else if (a == "--color") {
      o.colorField = value();
      if (!render::parseColorField(o.colorField)) {
        throw std::invalid_argument("--color expects one of " + std::string(render::colorFieldNames()) +
                                    ", got '" + o.colorField + "'");
      }
      colorGiven = true;
      viewOnly.push_back(a);
    } else if (a == "--highlight-time") {
      const double s = parseNumber(a, value());
      if (s < 0.0)
        throw std::invalid_argument("--highlight-time must be >= 0");
      o.highlightTime = s;
      viewOnly.push_back(a);
    } else if (a == "--no-spray") {
      o.noSpray = true;
      viewOnly.push_back(a);
    } else if (a == "--shaders") {
      o.shaderDir = value();
      viewOnly.push_back(a);
    } else if (a == "--hand-script") {
      o.handScript = value();
    } else if (a == "--hand-size") {
      o.handScale = parseNumber(a, value());
      if (o.handScale < 0.5 || o.handScale > 3.0)
        throw std::invalid_argument("--hand-size expects a number in [0.5, 3]");
    } else if (a == "--fixed-step") {
      o.fixedStep = true;
      windowOnly.push_back(a);
    } else if (a == "--time-scale") {
      o.timeScale = parseNumber(a, value());
      if (o.timeScale < 0.05 || o.timeScale > 4.0)
        throw std::invalid_argument("--time-scale expects a number in [0.05, 4]");
      windowOnly.push_back(a);
    } else if (a == "--screenshot") {
      o.screenshot = value();
      windowOnly.push_back(a);
    } else if (a == "--record-frames") {
      o.recordDir = value();
      windowOnly.push_back(a);
    } else if (a == "--fullscreen") {
      o.fullscreen = true;
      windowOnly.push_back(a);
    } else if (a == "--no-panel") {
      o.noPanel = true;
      windowOnly.push_back(a);
    } else {
      throw std::invalid_argument("unknown option '" + a + "'");
    }
  }
  if (o.frames && o.simTime)
    throw std::invalid_argument("--frames and --sim-time exclude each other");
  if (!o.render && !renderOnly.empty())
    throw std::invalid_argument(renderOnly.front() + " needs --render");
  if (o.headless && !o.render && !viewOnly.empty())
    throw std::invalid_argument(viewOnly.front() + " needs --render (or the window, without --headless)");
  if (o.headless && !windowOnly.empty())
    throw std::invalid_argument(windowOnly.front() + " applies to the window, not --headless");
  if (!o.headless && o.simTime)
    throw std::invalid_argument("--sim-time needs --headless (the window runs until closed or --frames)");
  if (o.render && o.outDir.empty())
    throw std::invalid_argument("--render needs --out DIR");
  if (colorGiven) {
    if (viewGiven && o.view == "fluid")
      throw std::invalid_argument("--color applies to --view particles, not --view fluid");
    o.view = "particles";
  }
  if (o.scenePath.empty())
    o.scenePath = o.headless ? defaultScenePath() : defaultAppScenePath();
  return o;
}

std::string assetPath(const std::string& relative) {
  if (std::filesystem::exists(relative))
    return relative;
  return std::string(FP_SOURCE_DIR) + "/" + relative;
}

std::string defaultAppScenePath() {
  return assetPath("assets/scenes/hand_tank.json");
}

std::string defaultScenePath() {
  return assetPath("assets/scenes/dam_break.json");
}

}  // namespace fp::engine
