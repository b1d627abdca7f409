#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/headless_runner.h"

namespace fp::engine {

void writeStatsJson(const std::string& path, const RunSummary& s) {
  nlohmann::ordered_json j;
  j["scene"] = s.scene;
  j["status"] = s.status;
  if (!s.message.empty())
    j["message"] = s.message;
  j["mode"] = s.mode;
  j["threads"] = s.threads;
  j["seed"] = s.seed;
  j["particles_mean"] = s.particlesMean;
  j["particles_max"] = s.particlesMax;
  j["particles_final"] = s.particlesFinal;
  j["boundary_particles"] = s.boundaryParticles;
  j["steps"] = s.steps;
  j["frames"] = s.frames;
  j["sim_seconds"] = s.simSeconds;
  j["wall_seconds"] = s.wallSeconds;
  j["us_per_particle_step"] = s.usPerParticleStep;
  j["density_error_mean"] = s.densityErrorMean;
  j["density_error_max"] = s.densityErrorMax;
  j["max_speed"] = s.maxSpeed;
  j["max_speed_time"] = s.maxSpeedTime;
  j["caged_particle_steps"] = s.cagedParticleSteps;
  j["density_iterations_mean"] = s.densityIterationsMean;
  j["divergence_iterations_mean"] = s.divergenceIterationsMean;
  j["neighbors_mean"] = s.neighborsMean;
  j["mass_initial"] = s.massInitial;
  j["mass_final"] = s.massFinal;
  j["mass_drift"] = s.massInitial > 0 ? (s.massFinal - s.massInitial) / s.massInitial : 0.0;
  j["momentum_final"] = {s.momentumFinal.x(), s.momentumFinal.y(), s.momentumFinal.z()};
  j["memory_bytes"] = s.memoryBytes;
  j["splits"] = s.adaptivity.splits;
  j["split_children"] = s.adaptivity.children;
  j["splits_blocked"] = s.adaptivity.splitsBlocked;
  j["merges"] = s.adaptivity.merges;
  j["redistributions"] = s.adaptivity.redistributions;
  j["split_error_reduction"] = s.adaptivity.splitErrorReduction();
  j["split_error_reduction_orientation"] = s.adaptivity.orientationErrorReduction();
  j["adaptivity_share"] = s.adaptivityShare;
  j["splash_particles"] = s.splashParticles;
  j["splash_height"] = s.splashHeight;
  j["splash_height_max"] = s.splashHeightMax;
  j["splash_height_with_splash"] = s.splashHeightWithSplash;
  j["splash_height_with_splash_max"] = s.splashHeightWithSplashMax;
  j["phase_seconds"] = {{"neighbors", s.phases.neighbors},   {"density", s.phases.density},
                        {"divergence", s.phases.divergence}, {"viscosity", s.phases.viscosity},
                        {"pressure", s.phases.pressure},     {"boundaries", s.phases.boundaries},
                        {"integrate", s.phases.integrate},   {"levels", s.phases.levels},
                        {"adaptation", s.phases.adaptation}};
  std::ofstream file(path);
  if (!file)
    throw sim::InputError(path + ": cannot open stats file for writing");
  file << j.dump(2) << "\n";
  if (!file)
    throw sim::InputError(path + ": write failed");
}

}  // namespace fp::engine
