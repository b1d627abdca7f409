#include "sim/params.h"

namespace fp::sim {

// The one declaration of every simulation parameter: key, group, unit, range, whether it may change while the
// simulation runs, description, member and default. Panel order.
ParamTable::ParamTable() : ParamTableOf<SimParams>("parameter", &ParamTable::validate) {
  using P = SimParams;
  const bool live = true;
  const bool onReset = false;
  // fluid
  add("particle_radius", "fluid", "m", 1e-3, 0.5, onReset,
      "radius r of the finest particles (spacing 2r, support 4r)", &P::particleRadius, 0.025);
  add("rest_density", "fluid", "kg/m^3", 100.0, 20000.0, onReset, "rest density rho0", &P::restDensity,
      1000.0);
  add("lattice_density", "fluid", "-", 0.5, 1.0, onReset,
      "density of the fluid blocks' starting lattice in units of rho0: 1 = at rest; 0.8 = the reference "
      "library's particle mass, 0.8 (2r)^3 rho0 (SPlisHSPlasH; such water settles to 0.8 of its block)",
      &P::latticeDensity, 1.0);
  add("gravity", "fluid", "m/s^2", -100.0, 100.0, live, "gravitational acceleration", &P::gravity,
      std::array<double, 3>{0.0, -9.81, 0.0});
  add("viscosity", "fluid", "-", 0.0, 1.0, live,
      "XSPH viscosity: share of the velocity difference smoothed per step", &P::viscosity, 0.01);
  add("boundary_viscosity", "fluid", "-", 0.0, 1.0, live, "XSPH friction against boundaries",
      &P::boundaryViscosity, 0.0);
  add("laminar_viscosity", "fluid", "m^2/s", 0.0, 1.0, live,
      "kinematic viscosity nu of a laminar (Laplacian) viscosity, 0 = off", &P::laminarViscosity, 0.0);
  add("surface_tension", "fluid", "-", 0.0, 10.0, live,
      "Akinci 2013 cohesion + curvature coefficient, 0 = off", &P::surfaceTension, 0.0);
  // time stepping
  add("cfl_factor", "time", "-", 0.01, 1.0, live, "CFL number: dt = cfl * 2r / max speed", &P::cflFactor,
      0.4);
  add("dt_max", "time", "s", 1e-5, 0.05, live, "largest time step", &P::dtMax, 0.005);
  add("dt_min", "time", "s", 1e-7, 0.01, live, "smallest time step", &P::dtMin, 1e-5);
  add("initial_relaxation", "time", "steps", 0, 1000, onReset,
      "damped steps settling the start in every mode (water at rest under its own weight; fluid blocks then "
      "take their initial velocities)",
      &P::initialRelaxation, 20);
  add("time_levels", "time stepping", "-", 1, 2, live,
      "1: one time step for all; 2: particles whose own CFL allows twice the step (and their neighbours'), "
      "twice the step within dt_max, skip the solves every other step and drift (docs/method.md, Time "
      "levels)",
      &P::timeLevels, 1);
  // pressure solver (DFSPH)
  add("density_tolerance", "solver", "%", 1e-4, 10.0, live, "allowed mean density error in percent of rho0",
      &P::densityTolerance, 0.1);
  add("divergence_tolerance", "solver", "%", 1e-4, 10.0, live,
      "allowed mean divergence error in percent of rho0 per time step", &P::divergenceTolerance, 0.1);
  add("min_iterations", "solver", "-", 1, 100, live, "least pressure iterations per solve", &P::minIterations,
      2);
  add("max_iterations", "solver", "-", 1, 1000, live, "most pressure iterations per solve", &P::maxIterations,
      100);
  add("divergence_solve", "solver", "-", 0, 1, live, "run the divergence-free solve", &P::divergenceSolve,
      true);
  add("warm_start", "solver", "-", 0, 1, live, "warm-start both solves with the previous step's stiffness",
      &P::warmStart, true);
  // adaptivity (docs/method.md, Levels and Adaptivity)
  add("mass_ratio", "adaptivity", "-", 1.0, 125.0, live,
      "m_base / m_fine: mass of the coarsest particles over the finest", &P::massRatio, 27.0);
  add("surface_distance_lo", "adaptivity", "r", 0.0, 1000.0, live,
      "distance to the surface below which particles are finest, R_phi = 0 (in fine radii)",
      &P::surfaceDistanceLo, 0.0);
  add("surface_distance_hi", "adaptivity", "r", 0.0, 1000.0, live,
      "distance to the surface above which particles are coarsest, R_phi = 1 (in fine radii)",
      &P::surfaceDistanceHi, 8.0);
  add("vorticity_lo", "adaptivity", "1/s", 0.0, 1e4, live,
      "vorticity at which refinement starts (R_omega = 1)", &P::vorticityLo, 6.0);
  add("vorticity_hi", "adaptivity", "1/s", 0.0, 1e4, live, "vorticity of full refinement (R_omega = Rmax)",
      &P::vorticityHi, 14.0);
  add("vorticity_rmax", "adaptivity", "-", 1.0, 1000.0, live, "largest vorticity level Rmax_omega",
      &P::vorticityRmax, 8.0);
  add("velocity_difference_lo", "adaptivity", "m/s", 0.0, 100.0, live,
      "velocity difference at which refinement starts (R_nu = 1)", &P::velocityDifferenceLo, 0.35);
  add("velocity_difference_hi", "adaptivity", "m/s", 0.0, 100.0, live,
      "velocity difference of full refinement (R_nu = Rmax)", &P::velocityDifferenceHi, 0.7);
  add("velocity_difference_rmax", "adaptivity", "-", 1.0, 1000.0, live,
      "largest velocity-difference level Rmax_nu", &P::velocityDifferenceRmax, 8.0);
  add("mass_smoothing", "adaptivity", "-", 0.01, 1.0, live,
      "share of the new optimal mass taken per solver step (1: no smoothing)", &P::massSmoothing, 0.25);
  add("adaptation_period", "adaptivity", "steps", 1, 100, live, "solver steps between adaptation steps",
      &P::adaptationPeriod, 1);
  add("levels_period", "adaptivity", "-", 1, 100, live,
      "adaptation steps between computations of the levels (the optimal masses in between are kept)",
      &P::levelsPeriod, 8);
  add("cfl_limited_refinement", "adaptivity", "-", 0, 1, live,
      "vorticity and velocity difference refine a particle only as far as keeps the time step the surface "
      "allows",
      &P::cflLimitedRefinement, true);
  add("split_delay", "adaptivity", "steps", 0, 100, live,
      "solver steps a particle must stay too heavy before it splits", &P::splitDelay, 13);
  add("split_max_children", "adaptivity", "-", 8, 27, live, "n_max: most children of one split",
      &P::splitMaxChildren, 27);
  add("orientation_candidates", "adaptivity", "-", 1, 64, live,
      "K: template rotations tried per split (the unrotated one included)", &P::orientationCandidates, 8);
  add("orientation_refinement", "adaptivity", "-", 0, 64, live,
      "tries turning the best of the K rotations about a random axis, kept when they lower the split error",
      &P::orientationRefinement, 8);
  add("split_position_steps", "adaptivity", "-", 0, 16, live,
      "steps moving the children of the chosen orientation down the gradient of the split error (their "
      "centre kept)",
      &P::splitPositionSteps, 3);
  add("merge_below", "adaptivity", "-", 0.0, 1.0, live, "m / m_opt below which a particle is merged",
      &P::mergeBelow, 0.51);
  add("light_below", "adaptivity", "-", 0.0, 1.0, live, "m / m_opt below which a particle may receive mass",
      &P::lightBelow, 0.9);
  add("merge_receivers_below", "adaptivity", "-", 0.0, 1.0, live,
      "m / m_opt below which a particle may receive a merged particle's mass (each up to its m_opt)",
      &P::mergeReceiversBelow, 1.0);
  add("share_above", "adaptivity", "-", 1.0, 10.0, live,
      "m / m_opt above which a particle shares mass with light neighbours", &P::shareAbove, 1.1);
  add("split_above", "adaptivity", "-", 1.0, 10.0, live, "m / m_opt at or above which a particle splits",
      &P::splitAbove, 1.99);
  add("transfer_rate", "adaptivity", "-", 0.01, 1.0, live,
      "most mass a merge or share receiver gains per solver step (share of its own); an adaptation every k "
      "steps moves k times as much, at most 0.1 at once (or transfer_rate, if higher)",
      &P::transferRate, 0.05);
  add("support_blend_steps", "adaptivity", "steps", 0, 100, live,
      "steps over which a changed support radius is blended in (0: at once)", &P::supportBlendSteps, 10);
  add("split_blend_steps", "adaptivity", "steps", 0, 100, live,
      "steps over which a split child's density and velocity are blended from its parent's (0: off; off by "
      "default: docs/method.md)",
      &P::splitBlendSteps, 0);
  // splash enhancement (docs/method.md, Splash)
  add("splash_enabled", "splash", "-", 0, 1, live, "generate splash particles (render only)",
      &P::splashEnabled, true);
  add("splash_neighbors", "splash", "-", 1, 200, live,
      "N_splash: surface particles with fewer fluid neighbours spawn splash", &P::splashNeighbors, 12);
  add("splash_count", "splash", "-", 0, 64, live, "n_splash: splash particles per spawning particle",
      &P::splashCount, 4);
  add("splash_alpha_min", "splash", "r", 0.0, 20.0, live, "alpha_min: smallest offset (particle radii)",
      &P::splashAlphaMin, 0.5);
  add("splash_alpha_max", "splash", "r", 0.0, 20.0, live, "alpha_max: largest offset (particle radii)",
      &P::splashAlphaMax, 3.0);
  add("splash_noise", "splash", "-", 0.0, 10.0, live,
      "n_r_max: length of the random direction added to the outward one", &P::splashNoise, 0.5);
  // robustness
  add("max_speed", "robustness", "m/s", 0.1, 1000.0, live,
      "speed above which a fluid particle is reported as an instability", &P::maxSpeed, 50.0);
  add("seed", "robustness", "-", 0, 4294967295.0, onReset,
      "seed of every random choice (sampling jitter, split orientations)", &P::seed, 1);
}

SimParams::SimParams() {
  ParamTable::sim().applyDefaults(*this);
}

bool operator==(const SimParams& a, const SimParams& b) {
  return ParamTable::sim().allEqual(a, b);
}

const ParamTable& ParamTable::sim() {
  static const ParamTable table;
  return table;
}

std::string ParamTable::validate(const SimParams& p) {
  if (p.dtMin > p.dtMax)
    return "dt_min must not exceed dt_max";
  if (p.minIterations > p.maxIterations)
    return "min_iterations must not exceed max_iterations";
  if (p.surfaceDistanceLo >= p.surfaceDistanceHi)
    return "surface_distance_lo must be below surface_distance_hi";
  if (p.vorticityLo >= p.vorticityHi)
    return "vorticity_lo must be below vorticity_hi";
  if (p.velocityDifferenceLo >= p.velocityDifferenceHi)
    return "velocity_difference_lo must be below velocity_difference_hi";
  if (p.splashAlphaMin > p.splashAlphaMax)
    return "splash_alpha_min must not exceed splash_alpha_max";
  if (!(p.mergeBelow < p.lightBelow && p.shareAbove < p.splitAbove))
    return "the thresholds must keep merge_below < light_below <= 1 <= share_above < split_above";
  if (!(p.mergeBelow < p.mergeReceiversBelow))
    return "the thresholds must keep merge_below < merge_receivers_below <= 1";
  return {};
}

}  // namespace fp::sim
