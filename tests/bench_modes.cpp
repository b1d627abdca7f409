/// fp_bench_modes: the paper's comparison. Runs one scene (default: the propeller) for the same simulated
/// time in each resolution mode, one after the other in this process, and prints one table row per mode plus
/// the same figures as CSV: wall time and speed-up against uniform-high, mean and max particle count as a
/// share of uniform-high, mean density error, the density error decrease from choosing split orientations,
/// and the share of step time spent on levels and adaptation.
///
///   fp_bench_modes [--scene FILE] [--sim-time S] [--modes a,b,..] [--threads T] [--set KEY=VALUE]...
///                  [--csv FILE] [--quick] [--help]

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/cli.h"
#include "engine/scene_loader.h"
#include "sim/simulation.h"

namespace {

using Clock = std::chrono::steady_clock;
using namespace fp;

const char* const kDefaultScene = FP_SOURCE_DIR "/assets/scenes/propeller.json";
constexpr double kDefaultSimTime = 2.0;
constexpr double kQuickSimTime = 0.3;

struct Row {
  std::string mode;
  std::string status = "ok";
  double wall = 0;
  std::uint64_t steps = 0;
  double particlesMean = 0;
  std::size_t particlesMax = 0;
  double densityError = 0;
  sim::AdaptivityStats adaptivity;
  double adaptivityShare = 0;
};

std::string usage() {
  return "usage: fp_bench_modes [--scene FILE] [--sim-time S] [--modes LIST] [--threads T] [--set "
         "KEY=VALUE]...\n"
         "                      [--csv FILE] [--quick] [--help]\n"
         "  --scene FILE     scene JSON (default assets/scenes/propeller.json)\n"
         "  --sim-time S     simulated seconds per mode (default 2; --quick: 0.3)\n"
         "  --modes LIST     comma-separated modes (default uniform-low,uniform-high,surface,fluidplaying)\n"
         "  --threads T      worker threads (default: all cores)\n"
         "  --set KEY=VALUE  override a parameter of the scene, e.g. --set particle_radius=0.006\n"
         "  --csv FILE       also write the table as CSV\n";
}

double parsePositive(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(v > 0))
    throw std::invalid_argument(flag + " expects a positive number, got '" + text + "'");
  return v;
}

Row runMode(sim::SceneDesc scene, sim::AdaptivityMode mode, double simTime) {
  scene.mode = mode;
  Row row;
  row.mode = sim::modeName(mode);
  const auto start = Clock::now();
  sim::Simulation simulation(scene);
  try {
    while (simulation.time() < simTime - 1e-12)
      simulation.step();
  } catch (const sim::InstabilityError& e) {
    row.status = e.what();
  }
  row.wall = std::chrono::duration<double>(Clock::now() - start).count();
  const sim::RunStats& run = simulation.runStats();
  row.steps = run.steps;
  row.particlesMean = run.steps ? double(run.particleSteps) / double(run.steps) : 0.0;
  row.particlesMax = run.particlesMax;
  row.densityError = run.steps ? run.densityErrorSum / double(run.steps) : 0.0;
  row.adaptivity = run.adaptivity;
  const double total = run.times.total();
  row.adaptivityShare = total > 0 ? (run.times.levels + run.times.adaptation) / total : 0.0;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath = kDefaultScene;
  double simTime = kDefaultSimTime;
  std::string csvPath;
  int threads = 0;
  std::vector<std::pair<std::string, double>> overrides;
  std::vector<sim::AdaptivityMode> modes = {sim::AdaptivityMode::UniformLow, sim::AdaptivityMode::UniformHigh,
                                            sim::AdaptivityMode::Surface, sim::AdaptivityMode::FluidPlaying};
  try {
    const std::vector<std::string> args(argv + 1, argv + argc);
    for (std::size_t k = 0; k < args.size(); ++k) {
      const std::string& a = args[k];
      auto value = [&]() -> const std::string& {
        if (k + 1 >= args.size())
          throw std::invalid_argument(a + " needs a value");
        return args[++k];
      };
      if (a == "--help") {
        std::cout << usage();
        return engine::kExitOk;
      } else if (a == "--scene") {
        scenePath = value();
      } else if (a == "--sim-time") {
        simTime = parsePositive(a, value());
      } else if (a == "--quick") {
        simTime = kQuickSimTime;
      } else if (a == "--threads") {
        threads = int(parsePositive(a, value()));
      } else if (a == "--csv") {
        csvPath = value();
      } else if (a == "--set") {
        const std::string kv = value();
        const std::size_t eq = kv.find('=');
        if (eq == std::string::npos)
          throw std::invalid_argument("--set expects KEY=VALUE, got '" + kv + "'");
        overrides.emplace_back(kv.substr(0, eq), std::stod(kv.substr(eq + 1)));
      } else if (a == "--modes") {
        modes.clear();
        std::stringstream list(value());
        std::string name;
        while (std::getline(list, name, ',')) {
          const auto m = sim::parseMode(name);
          if (!m)
            throw std::invalid_argument("unknown mode '" + name + "' (expected " + sim::modeNames() + ")");
          modes.push_back(*m);
        }
      } else {
        throw std::invalid_argument("unknown option '" + a + "'");
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "fp_bench_modes: " << e.what() << "\n" << usage();
    return engine::kExitUsage;
  }

  sim::SceneDesc scene;
  try {
    scene = engine::loadScene(scenePath);
    for (const auto& [key, v] : overrides) {
      const sim::ParamInfo* info = sim::ParamTable::sim().find(key);
      if (!info)
        throw sim::InputError("--set: unknown parameter '" + key + "'");
      const std::string error = sim::ParamTable::setScalar(scene.params, *info, v);
      if (!error.empty())
        throw sim::InputError("--set: " + error);
    }
  } catch (const sim::InputError& e) {
    std::cerr << "fp_bench_modes: " << e.what() << "\n";
    return engine::kExitInput;
  }
  if (threads <= 0)
    threads = int(tbb::info::default_concurrency());
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, std::size_t(threads));

  std::printf("fp_bench_modes: %s, r = %g m, mass ratio %g, %g s simulated per mode, %d threads\n",
              scene.name.c_str(), scene.params.particleRadius, scene.params.massRatio, simTime, threads);
  std::vector<Row> rows;
  for (sim::AdaptivityMode m : modes) {
    std::fprintf(stderr, "  running %s ...\n", sim::modeName(m));
    rows.push_back(runMode(scene, m, simTime));
  }
  const Row* high = nullptr;
  for (const Row& r : rows)
    if (r.mode == "uniform-high")
      high = &r;

  std::printf("\n%-13s %9s %7s %8s %10s %7s %9s %7s %10s %10s %9s\n", "mode", "wall [s]", "speedup", "steps",
              "particles", "share", "max", "share", "dens.err%", "orient.-%", "adapt.%");
  std::ostringstream csv;
  csv << "mode,status,wall_s,speedup_vs_uniform_high,steps,particles_mean,particles_mean_share,particles_max,"
         "particles_max_share,density_error_mean,split_error_reduction,adaptivity_share,splits,merges,"
         "redistributions\n";
  bool allOk = true;
  for (const Row& r : rows) {
    const double speedup = high && r.wall > 0 ? high->wall / r.wall : 0.0;
    const double meanShare = high && high->particlesMean > 0 ? r.particlesMean / high->particlesMean : 0.0;
    const double maxShare =
        high && high->particlesMax > 0 ? double(r.particlesMax) / double(high->particlesMax) : 0.0;
    std::printf("%-13s %9.2f %7.2f %8llu %10.0f %6.1f%% %9zu %6.1f%% %10.3f %10.1f %9.1f\n", r.mode.c_str(),
                r.wall, speedup, (unsigned long long)r.steps, r.particlesMean, 100 * meanShare,
                r.particlesMax, 100 * maxShare, 100 * r.densityError,
                100 * r.adaptivity.splitErrorReduction(), 100 * r.adaptivityShare);
    if (r.status != "ok") {
      std::printf("  %s: %s\n", r.mode.c_str(), r.status.c_str());
      allOk = false;
    }
    csv << r.mode << "," << (r.status == "ok" ? "ok" : "unstable") << "," << r.wall << "," << speedup << ","
        << r.steps << "," << r.particlesMean << "," << meanShare << "," << r.particlesMax << "," << maxShare
        << "," << r.densityError << "," << r.adaptivity.splitErrorReduction() << "," << r.adaptivityShare
        << "," << r.adaptivity.splits << "," << r.adaptivity.merges << "," << r.adaptivity.redistributions
        << "\n";
  }
  std::printf("\nCSV\n%s", csv.str().c_str());
  if (!csvPath.empty()) {
    std::ofstream file(csvPath);
    file << csv.str();
    if (!file) {
      std::cerr << "fp_bench_modes: cannot write " << csvPath << "\n";
      return engine::kExitInput;
    }
  }
  return allOk ? engine::kExitOk : engine::kExitUnstable;
}
