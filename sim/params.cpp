#include "sim/params.h"

#include <cmath>
#include <sstream>

namespace fp::sim {

namespace {
std::string formatRange(const ParamInfo& info) {
  std::ostringstream s;
  s << "[" << info.min << ", " << info.max << "]";
  return s.str();
}
}  // namespace

ParamTable::ParamTable() {
  using P = SimParams;
  auto add = [&](std::string key, std::string group, std::string unit, ParamKind kind, double min, double max,
                 bool live, std::string description, auto member) {
    m_entries.push_back(ParamInfo{std::move(key), std::move(group), std::move(unit), kind, min, max,
                                  std::move(description), live, member});
  };
  const ParamKind R = ParamKind::Number;
  const ParamKind I = ParamKind::Integer;
  const ParamKind B = ParamKind::Boolean;
  add("particle_radius", "fluid", "m", R, 1e-3, 0.5, false,
      "radius of the finest particles (spacing 2r, support 4r)", &P::particleRadius);
  add("rest_density", "fluid", "kg/m^3", R, 100.0, 20000.0, false, "rest density rho0", &P::restDensity);
  add("gravity", "fluid", "m/s^2", ParamKind::Vector3, -100.0, 100.0, true, "gravitational acceleration",
      &P::gravity);
  add("viscosity", "fluid", "-", R, 0.0, 1.0, true, "XSPH viscosity: velocity smoothing per step",
      &P::viscosity);
  add("boundary_viscosity", "fluid", "-", R, 0.0, 1.0, true, "XSPH friction against boundaries",
      &P::boundaryViscosity);
  add("surface_tension", "fluid", "-", R, 0.0, 10.0, true, "Akinci 2013 surface tension coefficient, 0 = off",
      &P::surfaceTension);
  add("cfl_factor", "time", "-", R, 0.01, 1.0, true, "CFL number: dt = cfl * 2r / max speed", &P::cflFactor);
  add("dt_max", "time", "s", R, 1e-5, 0.05, true, "largest time step", &P::dtMax);
  add("dt_min", "time", "s", R, 1e-7, 0.01, true, "smallest time step", &P::dtMin);
  add("initial_relaxation", "time", "steps", I, 0, 1000, false,
      "damped steps settling the coarsened start of the modes with coarse particles", &P::initialRelaxation);
  add("density_tolerance", "solver", "%", R, 1e-4, 10.0, true,
      "allowed mean density error in percent of rho0", &P::densityTolerance);
  add("divergence_tolerance", "solver", "%", R, 1e-4, 10.0, true,
      "allowed mean divergence error in percent of rho0 per time step", &P::divergenceTolerance);
  add("min_iterations", "solver", "-", I, 1, 100, true, "least pressure iterations per solve",
      &P::minIterations);
  add("max_iterations", "solver", "-", I, 1, 1000, true, "most pressure iterations per solve",
      &P::maxIterations);
  add("divergence_solve", "solver", "-", B, 0, 1, true, "run the divergence-free solve", &P::divergenceSolve);
  add("warm_start", "solver", "-", B, 0, 1, true, "warm-start solves with the previous stiffness",
      &P::warmStart);
  add("mass_ratio", "adaptivity", "-", R, 1.0, 125.0, true,
      "m_base / m_fine: mass of the coarsest particles over the finest", &P::massRatio);
  add("surface_distance_lo", "adaptivity", "r", R, 0.0, 1000.0, true,
      "distance to the surface below which particles are finest (in fine radii)", &P::surfaceDistanceLo);
  add("surface_distance_hi", "adaptivity", "r", R, 0.0, 1000.0, true,
      "distance to the surface above which particles are coarsest (in fine radii)", &P::surfaceDistanceHi);
  add("vorticity_lo", "adaptivity", "1/s", R, 0.0, 1e4, true, "vorticity at which refinement starts",
      &P::vorticityLo);
  add("vorticity_hi", "adaptivity", "1/s", R, 0.0, 1e4, true, "vorticity of full refinement (Rmax)",
      &P::vorticityHi);
  add("vorticity_rmax", "adaptivity", "-", R, 1.0, 1000.0, true, "largest vorticity level Rmax_omega",
      &P::vorticityRmax);
  add("velocity_difference_lo", "adaptivity", "m/s", R, 0.0, 100.0, true,
      "velocity difference at which refinement starts", &P::velocityDifferenceLo);
  add("velocity_difference_hi", "adaptivity", "m/s", R, 0.0, 100.0, true,
      "velocity difference of full refinement (Rmax)", &P::velocityDifferenceHi);
  add("velocity_difference_rmax", "adaptivity", "-", R, 1.0, 1000.0, true,
      "largest velocity-difference level Rmax_nu", &P::velocityDifferenceRmax);
  add("mass_smoothing", "adaptivity", "-", R, 0.01, 1.0, true,
      "share of the new optimal mass taken per adaptation step (1: none)", &P::massSmoothing);
  add("adaptation_period", "adaptivity", "steps", I, 1, 100, true, "solver steps between adaptation steps",
      &P::adaptationPeriod);
  add("split_delay", "adaptivity", "steps", I, 0, 100, true,
      "adaptation steps a particle stays too heavy before it splits", &P::splitDelay);
  add("split_max_children", "adaptivity", "-", I, 8, 27, true, "n_max: most children of one split",
      &P::splitMaxChildren);
  add("orientation_candidates", "adaptivity", "-", I, 1, 64, true,
      "K: template rotations tried per split (the unrotated one included)", &P::orientationCandidates);
  add("merge_below", "adaptivity", "-", R, 0.0, 1.0, true, "m/m_opt below which a particle is merged",
      &P::mergeBelow);
  add("light_below", "adaptivity", "-", R, 0.0, 1.0, true, "m/m_opt below which a particle receives mass",
      &P::lightBelow);
  add("share_above", "adaptivity", "-", R, 1.0, 10.0, true, "m/m_opt above which a particle shares mass",
      &P::shareAbove);
  add("split_above", "adaptivity", "-", R, 1.0, 10.0, true, "m/m_opt at or above which a particle splits",
      &P::splitAbove);
  add("transfer_rate", "adaptivity", "-", R, 0.01, 1.0, true,
      "most mass a merge or share receiver gains per adaptation step (share of its own)", &P::transferRate);
  add("support_blend_steps", "adaptivity", "steps", I, 0, 100, true,
      "steps over which a changed support radius is blended in (0: at once)", &P::supportBlendSteps);
  add("splash_enabled", "splash", "-", B, 0, 1, true, "generate splash particles (render only)",
      &P::splashEnabled);
  add("splash_neighbors", "splash", "-", I, 1, 200, true,
      "N_splash: surface particles with fewer neighbours spawn splash", &P::splashNeighbors);
  add("splash_count", "splash", "-", I, 0, 64, true, "n_splash: splash particles per spawning particle",
      &P::splashCount);
  add("splash_alpha_min", "splash", "r", R, 0.0, 20.0, true, "alpha_min: smallest offset (particle radii)",
      &P::splashAlphaMin);
  add("splash_alpha_max", "splash", "r", R, 0.0, 20.0, true, "alpha_max: largest offset (particle radii)",
      &P::splashAlphaMax);
  add("splash_noise", "splash", "-", R, 0.0, 10.0, true, "n_r_max: length of the random direction added",
      &P::splashNoise);
  add("max_speed", "robustness", "m/s", R, 0.1, 1000.0, true,
      "speed above which the run is reported unstable", &P::maxSpeed);
  add("seed", "robustness", "-", ParamKind::Seed, 0, 4294967295.0, false, "seed of every random choice",
      &P::seed);
}

const ParamTable& ParamTable::sim() {
  static const ParamTable table;
  return table;
}

const ParamInfo* ParamTable::find(std::string_view key) const {
  for (const ParamInfo& e : m_entries) {
    if (e.key == key)
      return &e;
  }
  return nullptr;
}

double ParamTable::getScalar(const SimParams& p, const ParamInfo& info) {
  return std::visit(
      [&](auto member) -> double {
        using M = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_same_v<M, std::array<double, 3>>) {
          return 0.0;
        } else {
          return static_cast<double>(p.*member);
        }
      },
      info.member);
}

std::array<double, 3> ParamTable::getVec3(const SimParams& p, const ParamInfo& info) {
  if (auto m = std::get_if<std::array<double, 3> SimParams::*>(&info.member))
    return p.**m;
  return {0.0, 0.0, 0.0};
}

std::string ParamTable::setScalar(SimParams& p, const ParamInfo& info, double value) {
  if (info.kind == ParamKind::Vector3)
    return info.key + " is a 3-vector";
  if (!std::isfinite(value))
    return info.key + " must be a finite number";
  if (value < info.min || value > info.max) {
    std::ostringstream s;
    s << info.key << " = " << value << " is out of range " << formatRange(info);
    return s.str();
  }
  if ((info.kind == ParamKind::Integer || info.kind == ParamKind::Seed) && value != std::floor(value)) {
    return info.key + " must be an integer";
  }
  std::visit(
      [&](auto member) {
        using M = std::decay_t<decltype(p.*member)>;
        if constexpr (!std::is_same_v<M, std::array<double, 3>>)
          p.*member = static_cast<M>(value);
      },
      info.member);
  return {};
}

std::string ParamTable::setVec3(SimParams& p, const ParamInfo& info, const std::array<double, 3>& value) {
  auto m = std::get_if<std::array<double, 3> SimParams::*>(&info.member);
  if (!m)
    return info.key + " is not a 3-vector";
  for (double c : value) {
    if (!std::isfinite(c) || c < info.min || c > info.max) {
      return info.key + " has a component out of range " + formatRange(info);
    }
  }
  p.** m = value;
  return {};
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
  return {};
}

}  // namespace fp::sim
