#pragma once
/// Measures of a simulation state used by the paper's experiment: how high the water reaches.

#include "sim/particle_set.h"
#include "sim/splash.h"

namespace fp::sim {

/// The height (y) below which `fraction` of the fluid's mass lies [m]. Weighted by mass, so that a mode with
/// fewer, heavier particles is measured on the same water (an unweighted percentile of a tenth as many
/// particles sits nearer the maximum). With `splash`, its particles count too, each weighing its source
/// particle's mass divided by `perSource` (n_splash). 0 for no particles.
double heightPercentile(const ParticleSet& p, double fraction, const SplashParticles* splash = nullptr,
                        int perSource = 1);

/// Mean density errors of a state, from the densities of its last step.
struct DensityErrorMeans {
  double perParticle = 0.0;     ///< mean over particles of max(0, rho / rho0 - 1) [-]
  double volumeWeighted = 0.0;  ///< the same weighted by rest volume m / rho0: a coarse particle of 27 fine
                                ///< masses counts 27 times [-]
};
/// The mean compression max(0, rho / rho0 - 1), per particle and volume-weighted; zeros for no particles.
DensityErrorMeans densityErrorMeans(const ParticleSet& p, double restDensity);

}  // namespace fp::sim
