#include "engine/cli.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

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
         "  --headless      run without a window or GL (the only mode of this build)\n"
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
         "exit codes: 0 ok, 2 bad command line, 3 bad scene or output, 4 simulation unstable\n";
}

CliOptions parseCommandLine(const std::vector<std::string>& args) {
  CliOptions o;
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
    } else {
      throw std::invalid_argument("unknown option '" + a + "'");
    }
  }
  if (o.frames && o.simTime)
    throw std::invalid_argument("--frames and --sim-time exclude each other");
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
