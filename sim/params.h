#pragma once
/// The simulation's parameter table: every simulation parameter declared once, in sim/params.cpp, with key,
/// group, unit, range, default, description and liveness. It drives the scene and preset readers, the GUI
/// panel, the command line's `--set KEY=VALUE` and validation of bad values.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sim/param_table.h"

namespace fp::sim {

/// All tunable parameters of the simulation core, as plain values. Their meaning, unit, range and default are
/// written once, in the table (ParamTable::sim(), sim/params.cpp); a default-constructed SimParams holds the
/// table's defaults. A new member needs a table entry (tests/test_params.cpp checks that every member has
/// one).
struct SimParams {
  /// every parameter at the table's default
  SimParams();

  // fluid
  double particleRadius;
  double restDensity;
  double latticeDensity;
  std::array<double, 3> gravity;
  double viscosity;
  double boundaryViscosity;
  double laminarViscosity;
  double surfaceTension;
  // time stepping
  double cflFactor;
  double dtMax;
  double dtMin;
  int initialRelaxation;
  int timeLevels;
  // pressure solver (DFSPH)
  double densityTolerance;
  double divergenceTolerance;
  int minIterations;
  int maxIterations;
  bool divergenceSolve;
  bool warmStart;
  // adaptivity (docs/method.md, Levels and Adaptivity); used by the surface and fluidplaying modes
  double massRatio;
  double surfaceDistanceLo;
  double surfaceDistanceHi;
  double vorticityLo;
  double vorticityHi;
  double vorticityRmax;
  double velocityDifferenceLo;
  double velocityDifferenceHi;
  double velocityDifferenceRmax;
  double massSmoothing;
  int adaptationPeriod;
  int levelsPeriod;
  bool cflLimitedRefinement;
  int splitDelay;
  int splitMaxChildren;
  int orientationCandidates;
  int orientationRefinement;
  int splitPositionSteps;
  double mergeBelow;
  double lightBelow;
  double mergeReceiversBelow;
  double shareAbove;
  double splitAbove;
  double transferRate;
  int supportBlendSteps;
  int splitBlendSteps;
  // splash enhancement (docs/method.md, Splash): render-only post-process, never fed back into the simulation
  bool splashEnabled;
  int splashNeighbors;
  int splashCount;
  double splashAlphaMin;
  double splashAlphaMax;
  double splashNoise;
  // robustness
  double maxSpeed;
  std::uint64_t seed;
};

/// whether every parameter of the table is the same in `a` and `b`
bool operator==(const SimParams& a, const SimParams& b);
/// whether some parameter of the table differs between `a` and `b`
inline bool operator!=(const SimParams& a, const SimParams& b) {
  return !(a == b);
}

/// Declaration of one simulation parameter.
using ParamInfo = ParamEntry<SimParams>;

/// The table of all simulation parameters, immutable. Besides the generic ParamTableOf operations (find, at,
/// visit over the value type, setText, assign, helpLines), it checks the relations between parameters.
///
/// For the command line (`--set KEY=VALUE`, `--seed N`):
///   /// applies "KEY=VALUE" to p; "" or the table's one-line error (unknown key with suggestion, type,
///   range) std::string error = ParamTable::sim().assign(p, "dt_max=0.002");
///   /// applies a list in order, then checks the relations (dt_min <= dt_max, ...)
///   std::string error = ParamTable::sim().assignAll(p, {"dt_min=1e-4", "dt_max=0.002"});
///   /// a parameter's range
///   const ParamInfo& seed = ParamTable::sim().at("seed");  // seed.min, seed.max
class ParamTable : public ParamTableOf<SimParams> {
 public:
  /// the simulation's table
  static const ParamTable& sim();

  /// checks relations between parameters (e.g. dt_min <= dt_max); returns an error message or empty
  static std::string validate(const SimParams& p);

 private:
  ParamTable();
};

}  // namespace fp::sim
