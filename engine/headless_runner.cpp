#include "engine/headless_runner.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <memory>

#include "engine/scene_loader.h"
#include "sim/metrics.h"
#include "sim/ply_writer.h"
#include "sim/splash.h"
#include "sim/state_io.h"

namespace fp::engine {

namespace {
using Clock = std::chrono::steady_clock;
constexpr double kSplashHeightFraction = 0.999;

void exportFrame(const std::string& dir, int frame, const sim::ParticleSet& particles) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%05d.ply", frame);
  sim::writePly((std::filesystem::path(dir) / name).string(), particles);
}
}  // namespace

void fillRunFigures(const sim::Simulation& simulation, RunSummary& s) {
  const sim::RunStats& run = simulation.runStats();
  s.steps = run.steps;
  s.simSeconds = simulation.time();
  s.particlesFinal = simulation.particles().size();
  s.particlesMean = run.steps ? double(run.particleSteps) / double(run.steps) : double(s.particlesFinal);
  s.particlesMax = std::max(run.particlesMax, s.particlesFinal);
  s.usPerParticleStep = run.particleSteps ? s.wallSeconds * 1e6 / double(run.particleSteps) : 0.0;
  if (run.steps) {
    s.densityErrorMean = run.densityErrorSum / double(run.steps);
    s.densityErrorMax = run.densityErrorMax;
    s.densityIterationsMean = double(run.densityIterations) / double(run.steps);
    s.divergenceIterationsMean = double(run.divergenceIterations) / double(run.steps);
    s.neighborsMean = run.neighborsSum / double(run.steps);
  }
  s.massFinal = simulation.totalMass();
  s.momentumFinal = simulation.totalMomentum();
  s.memoryBytes = simulation.memoryBytes();
  s.phases = run.times;
  s.adaptivity = run.adaptivity;
  const double stepTime = run.times.total();
  s.adaptivityShare = stepTime > 0 ? (run.times.levels + run.times.adaptation) / stepTime : 0.0;
}

RunSummary runHeadless(const CliOptions& options, std::ostream& out, std::ostream& progress,
                       const FrameCallback& onFrame) {
  sim::SceneDesc scene = loadScene(options.scenePath);
  overrideScene(scene, {options.mode, options.seed, options.sets});
  const int threads = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

  double simTime = scene.simTime;
  if (options.simTime)
    simTime = *options.simTime;
  if (options.frames)
    simTime = double(*options.frames) / scene.frameRate;
  if (!options.exportDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.exportDir, ec);
    if (ec)
      throw sim::InputError(options.exportDir + ": cannot create export directory (" + ec.message() + ")");
  }

  sim::Simulation simulation(scene);
  if (!options.loadState.empty())
    sim::loadState(options.loadState, simulation);
  RunSummary s;
  s.scene = options.scenePath;
  s.mode = sim::modeName(scene.mode);
  s.threads = threads;
  s.seed = scene.params.seed;
  s.boundaryParticles = simulation.boundary().size();
  s.massInitial = simulation.totalMass();
  out << "scene " << scene.name << " (" << s.mode << "): " << simulation.particles().size()
      << " fluid particles, " << simulation.boundary().size() << " boundary particles, " << threads
      << " threads, " << simTime << " s to simulate\n";

  const double frameDt = 1.0 / scene.frameRate;
  // a loaded state resumes at its frame (states are saved at frame ends)
  int frame = int(std::lround(simulation.time() / frameDt));
  // Splash and the height the water reaches are measured every frame (the paper's splash height: the height
  // below which 99.9 % of the mass lies, above its value at rest, i.e. at frame 0).
  sim::SplashGenerator splash;
  double restHeight = 0.0;
  const int firstFrame = frame;
  auto measure = [&]() {
    const sim::SplashParticles& sp = splash.generate(simulation, std::uint64_t(frame));
    const double h = sim::heightPercentile(simulation.particles(), kSplashHeightFraction);
    const double hs = sim::heightPercentile(simulation.particles(), kSplashHeightFraction, &sp,
                                            simulation.params().splashCount);
    if (frame == firstFrame)
      restHeight = h;
    s.splashParticles += double(sp.size());
    s.splashHeight += h - restHeight;
    s.splashHeightWithSplash += hs - restHeight;
    s.splashHeightMax = std::max(s.splashHeightMax, h - restHeight);
    s.splashHeightWithSplashMax = std::max(s.splashHeightWithSplashMax, hs - restHeight);
  };
  if (!options.exportDir.empty())
    exportFrame(options.exportDir, frame, simulation.particles());
  measure();
  if (onFrame)
    onFrame(frame, simulation);
  const auto start = Clock::now();
  auto lastReport = start;
  try {
    while (simulation.time() < simTime - 1e-12) {
      simulation.step();
      if (simulation.time() >= (frame + 1) * frameDt - 1e-12) {
        ++frame;
        if (!options.exportDir.empty())
          exportFrame(options.exportDir, frame, simulation.particles());
        measure();
        if (onFrame)
          onFrame(frame, simulation);
        if (options.saveEvery > 0 && frame % options.saveEvery == 0)
          sim::saveState(options.saveState, simulation);
      }
      const auto now = Clock::now();
      if (!options.quiet && std::chrono::duration<double>(now - lastReport).count() > 2.0) {
        lastReport = now;
        const double wall = std::chrono::duration<double>(now - start).count();
        const double eta = wall / simulation.time() * (simTime - simulation.time());
        progress << std::fixed << std::setprecision(3) << "  t = " << simulation.time() << " / " << simTime
                 << " s, step " << simulation.stepCount() << ", " << simulation.particles().size()
                 << " particles, wall " << std::setprecision(1) << wall << " s, eta " << eta << " s\n"
                 << std::defaultfloat << std::flush;
      }
    }
  } catch (const sim::InstabilityError& e) {
    s.status = "unstable";
    s.message = e.what();
  }
  if (!options.saveState.empty() && s.status == "ok")
    sim::saveState(options.saveState, simulation);
  s.wallSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  s.splashParticles /= double(frame - firstFrame + 1);
  s.splashHeight /= double(frame - firstFrame + 1);
  s.splashHeightWithSplash /= double(frame - firstFrame + 1);
  s.frames = frame;
  fillRunFigures(simulation, s);
  return s;
}

void printSummary(std::ostream& out, const RunSummary& s) {
  out << std::setprecision(6);
  if (s.status != "ok")
    out << "ERROR: " << s.message << "\n";
  out << "particles            " << s.particlesFinal << " (mean " << s.particlesMean << ", max "
      << s.particlesMax << ")\n"
      << "steps                " << s.steps << "\n"
      << "simulated time       " << s.simSeconds << " s\n"
      << "wall time            " << s.wallSeconds << " s\n"
      << "us per particle-step " << s.usPerParticleStep << "\n"
      << "density error        mean " << 100.0 * s.densityErrorMean << " %, max " << 100.0 * s.densityErrorMax
      << " %\n"
      << "solver iterations    density " << s.densityIterationsMean << ", divergence "
      << s.divergenceIterationsMean << " per step\n"
      << "adaptivity           " << s.adaptivity.splits << " splits, " << s.adaptivity.merges << " merges, "
      << s.adaptivity.redistributions << " redistributions, split error -"
      << 100.0 * s.adaptivity.splitErrorReduction() << " % by orientation, " << 100.0 * s.adaptivityShare
      << " % of step time\n"
      << "splash               " << s.splashParticles << " particles a frame, height "
      << 1000.0 * s.splashHeight << " mm (max " << 1000.0 * s.splashHeightMax << "), with splash "
      << 1000.0 * s.splashHeightWithSplash << " mm (max " << 1000.0 * s.splashHeightWithSplashMax << ")\n"
      << "total mass           " << s.massInitial << " kg -> " << s.massFinal << " kg (drift "
      << (s.massInitial > 0 ? (s.massFinal - s.massInitial) / s.massInitial : 0.0) << ")\n";
}

}  // namespace fp::engine
