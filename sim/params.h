#pragma once
/// The typed parameter table: every simulation parameter declared once with name, unit, range, default and a
/// one-line description. It drives scene loading and validation and the GUI panel (after SPlisHSPlasH's
/// `initParameters`, without its global registry).

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace fp::sim {

/// All tunable parameters of the simulation core. Plain values; the table below gives their meaning and
/// ranges.
struct SimParams {
  // fluid
  double particleRadius = 0.025;  ///< radius r of the finest particles [m]; spacing is 2r, support 4r
  double restDensity = 1000.0;    ///< rest density rho0 [kg/m^3]
  std::array<double, 3> gravity{0.0, -9.81, 0.0};  ///< gravitational acceleration [m/s^2]
  double viscosity = 0.01;         ///< XSPH viscosity: share of the velocity difference smoothed per step [-]
  double boundaryViscosity = 0.0;  ///< XSPH friction against boundaries [-]
  double surfaceTension = 0.0;     ///< Akinci 2013 cohesion + curvature coefficient, 0 = off [-]
  // time stepping
  double cflFactor = 0.4;  ///< CFL number: dt = cfl * 2r / v_max [-]
  double dtMax = 0.005;    ///< largest time step [s]
  double dtMin = 1e-5;     ///< smallest time step [s]
  int initialRelaxation =
      20;  ///< steps of damped settling before t = 0 in the modes with coarse particles [-]
  // pressure solver (DFSPH)
  double densityTolerance = 0.1;     ///< allowed mean density error [% of rho0]
  double divergenceTolerance = 0.1;  ///< allowed mean divergence error [% of rho0 per second * dt]
  int minIterations = 2;             ///< least solver iterations per solve
  int maxIterations = 100;           ///< most solver iterations per solve
  bool divergenceSolve = true;       ///< run the divergence-free solve
  bool warmStart = true;             ///< warm-start both solves with the previous step's stiffness
  // adaptivity (docs/method.md, Levels and Adaptivity); used by the surface and fluidplaying modes
  double massRatio = 27.0;          ///< m_base / m_fine: mass of the coarsest particles over the finest [-]
  double surfaceDistanceLo = 2.0;   ///< phi below this is fully fine (R_phi = 0) [fine radii r]
  double surfaceDistanceHi = 12.0;  ///< phi above this is fully coarse (R_phi = 1) [fine radii r]
  double vorticityLo = 6.0;         ///< omega below this does not refine (R_omega = 1) [1/s]
  double vorticityHi = 14.0;        ///< omega above this refines fully (R_omega = Rmax) [1/s]
  double vorticityRmax = 8.0;       ///< largest vorticity level Rmax_omega [-]
  double velocityDifferenceLo = 0.35;   ///< nu below this does not refine (R_nu = 1) [m/s]
  double velocityDifferenceHi = 0.7;    ///< nu above this refines fully (R_nu = Rmax) [m/s]
  double velocityDifferenceRmax = 8.0;  ///< largest velocity-difference level Rmax_nu [-]
  double massSmoothing =
      0.25;  ///< share of the new optimal mass taken per adaptation step (1: no smoothing) [-]
  int adaptationPeriod = 1;       ///< solver steps between adaptation steps [-]
  int splitDelay = 13;            ///< adaptation steps a particle must stay too heavy before it splits [-]
  int splitMaxChildren = 27;      ///< n_max: most children of one split [-]
  int orientationCandidates = 8;  ///< K: template rotations tried per split, the unrotated one included [-]
  double mergeBelow = 0.51;       ///< m / m_opt below this: too light, merged into neighbours [-]
  double lightBelow = 0.9;        ///< m / m_opt below this: light, may receive mass [-]
  double shareAbove = 1.1;        ///< m / m_opt above this: heavy, shares mass with light neighbours [-]
  double splitAbove = 1.99;       ///< m / m_opt at or above this: too heavy, split [-]
  double transferRate = 0.05;     ///< most mass a receiver gains per adaptation step, share of its own [-]
  int supportBlendSteps = 10;  ///< steps over which a changed support radius is blended in (0: at once) [-]
  // splash enhancement (docs/method.md, Splash): render-only post-process, never fed back into the simulation
  bool splashEnabled = true;    ///< generate splash particles
  int splashNeighbors = 12;     ///< N_splash: surface particles with fewer fluid neighbours spawn splash [-]
  int splashCount = 4;          ///< n_splash: temporary particles per spawning particle [-]
  double splashAlphaMin = 0.5;  ///< alpha_min: smallest offset from the particle [its radii]
  double splashAlphaMax = 3.0;  ///< alpha_max: largest offset from the particle [its radii]
  double splashNoise = 0.5;     ///< n_r_max: length of the random direction added to the outward one [-]
  // robustness
  double maxSpeed = 50.0;  ///< a fluid particle faster than this is reported as an instability [m/s]
  std::uint64_t seed = 1;  ///< seed of every random choice (sampling jitter, split orientations) [-]
};

/// Kind of value a parameter holds.
enum class ParamKind { Number, Integer, Boolean, Vector3, Seed };

/// Declaration of one parameter.
struct ParamInfo {
  std::string key;          ///< scene-file key, snake_case
  std::string group;        ///< panel group
  std::string unit;         ///< SI unit or "-"
  ParamKind kind;           ///< value kind
  double min;               ///< smallest allowed value (each component for Vec3)
  double max;               ///< largest allowed value (each component for Vec3)
  std::string description;  ///< one line
  bool live;                ///< may change while the simulation runs
  std::variant<double SimParams::*, int SimParams::*, bool SimParams::*, std::array<double, 3> SimParams::*,
               std::uint64_t SimParams::*>
      member;  ///< where the value lives
};

/// The table of all simulation parameters, immutable.
class ParamTable {
 public:
  /// the simulation's table
  static const ParamTable& sim();

  /// every parameter, in panel order
  const std::vector<ParamInfo>& entries() const { return m_entries; }
  /// the declaration named `key`, or nullptr
  const ParamInfo* find(std::string_view key) const;

  /// value of a scalar parameter (Number, Integer, Boolean, Seed) as double
  static double getScalar(const SimParams& p, const ParamInfo& info);
  /// value of a Vector3 parameter
  static std::array<double, 3> getVec3(const SimParams& p, const ParamInfo& info);
  /// sets a scalar parameter; returns an error message (empty on success) when out of range or not integral
  static std::string setScalar(SimParams& p, const ParamInfo& info, double value);
  /// sets a Vector3 parameter; returns an error message (empty on success) when a component is out of range
  static std::string setVec3(SimParams& p, const ParamInfo& info, const std::array<double, 3>& value);

  /// checks relations between parameters (e.g. dt_min <= dt_max); returns an error message or empty
  static std::string validate(const SimParams& p);

 private:
  ParamTable();
  std::vector<ParamInfo> m_entries;
};

}  // namespace fp::sim
