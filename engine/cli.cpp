#include "engine/cli.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "render/particle_colors.h"
#include "sim/scene.h"

namespace fp::engine {

namespace {

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

}  // namespace

std::string usage() {
  return "usage: fluidplaying [--headless] [--scene FILE] [--frames N | --sim-time S] [--threads T] [--seed "
         "N]\n"
         "                    [--mode NAME] [--stats FILE.json] [--export DIR] [--quiet] [--help]\n"
         "                    [--render --out DIR [--width W] [--height H] [--view fluid|particles] "
         "[--color FIELD]\n"
         "                     [--highlight-time S] [--no-spray] [--shaders DIR]]\n"
         "  --headless      run without a window (the only mode of this build)\n"
         "  --scene FILE    scene JSON (default assets/scenes/dam_break.json)\n"
         "  --frames N      simulate N frames at the scene's frame rate\n"
         "  --sim-time S    simulate S seconds (default: the scene's sim_time)\n"
         "  --threads T     worker threads (default: all cores)\n"
         "  --seed N        seed of every random choice (overrides the scene)\n"
         "  --mode NAME     resolution: uniform-low, uniform-high, surface or fluidplaying (default: the "
         "scene's)\n"
         "  --stats FILE    write the run's statistics as JSON\n"
         "  --export DIR    write the particles of every frame as binary PLY into DIR\n"
         "  --quiet         no progress lines\n"
         "  --render        render every frame (frame 0 is the initial state) offscreen through OSMesa, no\n"
         "                  display needed, and write DIR/frame_NNNNN.png; implies --headless\n"
         "  --out DIR       folder of the images (required with --render)\n"
         "  --width W       image width in pixels (default 1280)\n"
         "  --height H      image height in pixels (default 720)\n"
         "  --view NAME     fluid (screen-space water, default) or particles (spheres coloured by --color)\n"
         "  --color FIELD   particle view colour: mass, phi, omega, nu, speed or density-error (default nu)\n"
         "  --highlight-time S  tint split children red for S seconds after their split (default 0.5; 0: "
         "off)\n"
         "  --no-spray      do not draw splash particles\n"
         "  --shaders DIR   GLSL folder (default: shaders/ here, else the source tree's)\n"
         "exit codes: 0 ok, 2 bad command line, 3 bad scene, output or shader, 4 simulation unstable\n";
}

CliOptions parseCommandLine(const std::vector<std::string>& args) {
  CliOptions o;
  std::vector<std::string> renderOnly;  // options that mean nothing without --render
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
      renderOnly.push_back(a);
    } else if (a == "--view") {
      o.view = value();
      if (o.view != "fluid" && o.view != "particles")
        throw std::invalid_argument("--view expects fluid or particles, got '" + o.view + "'");
      viewGiven = true;
      renderOnly.push_back(a);
    } else if (a == "--color") {
      o.colorField = value();
      if (!render::parseColorField(o.colorField)) {
        throw std::invalid_argument("--color expects one of " + std::string(render::colorFieldNames()) +
                                    ", got '" + o.colorField + "'");
      }
      colorGiven = true;
      renderOnly.push_back(a);
    } else if (a == "--highlight-time") {
      const double s = parseNumber(a, value());
      if (s < 0.0)
        throw std::invalid_argument("--highlight-time must be >= 0");
      o.highlightTime = s;
      renderOnly.push_back(a);
    } else if (a == "--no-spray") {
      o.noSpray = true;
      renderOnly.push_back(a);
    } else if (a == "--shaders") {
      o.shaderDir = value();
      renderOnly.push_back(a);
    } else {
      throw std::invalid_argument("unknown option '" + a + "'");
    }
  }
  if (o.frames && o.simTime)
    throw std::invalid_argument("--frames and --sim-time exclude each other");
  if (!o.render && !renderOnly.empty())
    throw std::invalid_argument(renderOnly.front() + " needs --render");
  if (o.render && o.outDir.empty())
    throw std::invalid_argument("--render needs --out DIR");
  if (colorGiven) {
    if (viewGiven && o.view == "fluid")
      throw std::invalid_argument("--color applies to --view particles, not --view fluid");
    o.view = "particles";
  }
  if (o.scenePath.empty())
    o.scenePath = defaultScenePath();
  return o;
}

std::string defaultScenePath() {
  const std::string rel = "assets/scenes/dam_break.json";
  if (std::filesystem::exists(rel))
    return rel;
  return std::string(FP_SOURCE_DIR) + "/" + rel;
}

}  // namespace fp::engine
