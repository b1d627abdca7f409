#pragma once
/// The headless mode: runs a scene with no display and no GL (alone, or with a recorded hand replayed)
/// through the app loop in fixed frame steps, shows progress, prints a closing summary, and optionally writes
/// statistics as JSON and particles per frame as PLY.

#include <functional>
#include <ostream>
#include <string>

#include "engine/cli.h"
#include "sim/simulation.h"
#include "sim/splash.h"

namespace fp::engine {

/// What a run measured; written to the stats JSON under the names in the comments.
struct RunSummary {
  std::string scene;                  ///< "scene"
  std::string mode;                   ///< "mode": uniform-low | uniform-high | surface | fluidplaying
  std::string status = "ok";          ///< "status": ok | unstable
  std::string message;                ///< "message": the instability report, if any
  int threads = 0;                    ///< "threads"
  std::uint64_t seed = 0;             ///< "seed"
  double particlesMean = 0;           ///< "particles_mean"
  std::size_t particlesMax = 0;       ///< "particles_max"
  std::size_t particlesFinal = 0;     ///< "particles_final"
  std::size_t boundaryParticles = 0;  ///< "boundary_particles"
  std::uint64_t steps = 0;            ///< "steps"
  int frames = 0;                     ///< "frames"
  double simSeconds = 0;              ///< "sim_seconds"
  double wallSeconds = 0;             ///< "wall_seconds"
  double usPerParticleStep = 0;       ///< "us_per_particle_step"
  double densityErrorMean = 0;        ///< "density_error_mean": mean over steps of the mean compression [-]
  double densityErrorMax = 0;         ///< "density_error_max": largest per-step mean compression [-]
  double maxSpeed = 0;                ///< "max_speed": the fastest fluid particle's speed over the run [m/s]
  double maxSpeedTime = 0;            ///< "max_speed_time": the simulated time at which it came [s]
  std::uint64_t cagedParticleSteps = 0;  ///< "caged_particle_steps": particle-steps moved with their cage
  double densityIterationsMean = 0;      ///< "density_iterations_mean"
  double divergenceIterationsMean = 0;   ///< "divergence_iterations_mean"
  double neighborsMean = 0;              ///< "neighbors_mean": fluid + boundary neighbours per particle
  double massInitial = 0;                ///< "mass_initial" [kg]
  double massFinal = 0;                  ///< "mass_final" [kg]
  sim::Vec3d momentumFinal{0, 0, 0};     ///< "momentum_final" [kg m/s]
  std::size_t memoryBytes = 0;           ///< "memory_bytes"
  sim::PhaseTimes phases;                ///< "phase_seconds"
  double splashParticles = 0;            ///< "splash_particles": splash particles per frame, mean
  double splashHeight = 0;     ///< "splash_height": mean over frames of the 99.9 % mass height above rest [m]
  double splashHeightMax = 0;  ///< "splash_height_max": its largest value [m]
  double splashHeightWithSplash = 0;     ///< "splash_height_with_splash": the same with splash particles [m]
  double splashHeightWithSplashMax = 0;  ///< "splash_height_with_splash_max" [m]
  sim::AdaptivityStats adaptivity;  ///< "splits", "merges", "redistributions", "split_error_reduction", ...
  double adaptivityShare = 0;       ///< "adaptivity_share": share of step time in levels and adaptation [-]
};

/// Called with every frame (frame 0 is the initial state), after the PLY export, with the frame's splash
/// particles (generated once a frame for the figures): the headless renderer writes its images here.
using FrameCallback =
    std::function<void(int frame, const sim::Simulation& simulation, const sim::SplashParticles& splash)>;

/// Runs the scene of `options` headless through the app loop (sim/ steps in fixed frames of the scene up to
/// --frames, --sim-time or the scene's sim_time; the hand of --hand-script replayed in it when given). Throws
/// sim::InputError for a bad scene, hand script or unwritable output, std::invalid_argument for a bad
/// setting; an instability ends the run and is reported in the summary (status "unstable").
RunSummary runHeadless(const CliOptions& options, std::ostream& out, std::ostream& progress,
                       const FrameCallback& onFrame = {});

/// Fills the figures of a finished run from the simulation's run statistics (steps, particles, density error,
/// iterations, mass, momentum, memory, phases, adaptivity); `s.wallSeconds` must be set first.
void fillRunFigures(const sim::Simulation& simulation, RunSummary& s);

/// Writes a summary as JSON; throws sim::InputError when the file cannot be written.
void writeStatsJson(const std::string& path, const RunSummary& summary);

/// Prints the closing summary, one figure a line.
void printSummary(std::ostream& out, const RunSummary& summary);

}  // namespace fp::engine
