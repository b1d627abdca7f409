#include "engine/headless_runner.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>

#include "engine/headless_app.h"
#include "engine/tracked_hands.h"

namespace fp::engine {

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
    s.maxSpeed = run.maxSpeed;
    s.maxSpeedTime = run.maxSpeedTime;
    s.cagedParticleSteps = run.cagedParticleSteps;
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
  if (!options.exportDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.exportDir, ec);
    if (ec)
      throw sim::InputError(options.exportDir + ": cannot create export directory (" + ec.message() + ")");
  }
  const std::optional<JointReplay> joints = JointReplay::ofScript(options.handScript);
  SessionConfig config = sessionConfigOf(options);
  config.fixedStep = true;                   // no wall clock: every frame is 1 / frame_rate
  config.hand = !config.handScript.empty();  // the scene alone, unless a recorded hand plays in it
  config.recover = false;                    // an instability ends the run (exit 4)
  AppSession session(config);
  const sim::SceneDesc& scene = session.scene();
  double simTime = scene.simTime;
  if (options.simTime)
    simTime = *options.simTime;
  if (options.frames)
    simTime = double(*options.frames) / scene.frameRate;
  // a loaded state: the run goes on from its frame, so it ends where the uninterrupted run would
  const double startTime = std::round(session.simulation().time() * scene.frameRate) / scene.frameRate;
  session.setEndTime(startTime + simTime);

  const sim::Simulation& simulation = session.simulation();
  RunSummary s;
  s.scene = options.scenePath;
  s.mode = sim::modeName(simulation.mode());
  s.threads = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  s.seed = simulation.params().seed;
  s.boundaryParticles = simulation.boundary().size();
  s.massInitial = simulation.totalMass();
  if (options.handScript.empty()) {
    out << "scene " << scene.name << " (" << s.mode << "): " << simulation.particles().size()
        << " fluid particles, " << simulation.boundary().size() << " boundary particles, " << s.threads
        << " threads, " << simTime << " s to simulate\n";
  } else if (!options.quiet) {
    out << "scene " << scene.name << " (" << s.mode << ") with the hand replaying " << options.handScript
        << ": " << simulation.particles().size() << " fluid particles, " << simulation.boundary().size()
        << " boundary particles, " << s.threads << " threads, " << simTime << " s to simulate\n";
  }

  HeadlessPlatform platform(options, scene.frameRate, simTime, s, progress, onFrame);
  platform.setStartTime(startTime);
  JointReplayPlatform replay(platform, joints, session, options.handScale);
  runAppLoop(session, replay, std::nullopt);
  s.wallSeconds = platform.wallSeconds();
  s.frames = platform.frames();
  const double taken = double(std::max(s.frames, 0) + 1);
  s.splashParticles /= taken;
  s.splashHeight /= taken;
  s.splashHeightWithSplash /= taken;
  fillRunFigures(session.simulation(), s);
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
      << "fastest particle     " << s.maxSpeed << " m/s (t = " << s.maxSpeedTime << " s); "
      << s.cagedParticleSteps << " particle-steps caged by boundaries\n"
      << "solver iterations    density " << s.densityIterationsMean << ", divergence "
      << s.divergenceIterationsMean << " per step\n"
      << "adaptivity           " << s.adaptivity.splits << " splits, " << s.adaptivity.merges << " merges, "
      << s.adaptivity.redistributions << " redistributions, split error -"
      << 100.0 * s.adaptivity.splitErrorReduction() << " % (-"
      << 100.0 * s.adaptivity.orientationErrorReduction() << " % by orientation), "
      << 100.0 * s.adaptivityShare << " % of step time\n"
      << "splash               " << s.splashParticles << " particles a frame, height "
      << 1000.0 * s.splashHeight << " mm (max " << 1000.0 * s.splashHeightMax << "), with splash "
      << 1000.0 * s.splashHeightWithSplash << " mm (max " << 1000.0 * s.splashHeightWithSplashMax << ")\n"
      << "total mass           " << s.massInitial << " kg -> " << s.massFinal << " kg (drift "
      << (s.massInitial > 0 ? (s.massFinal - s.massInitial) / s.massInitial : 0.0) << ")\n";
}

}  // namespace fp::engine
