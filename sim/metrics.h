#pragma once
/// Measures of a simulation state used by the paper's experiment and the physics tests: how high the water
/// reaches, how far a surge runs, how compressed the water is, what time steps per particle could save.

#include "sim/particle_set.h"
#include "sim/splash.h"

namespace fp::sim {

/// The height (y) below which `fraction` of the fluid's mass lies [m]. Weighted by mass, so that a mode with
/// fewer, heavier particles is measured on the same water (an unweighted percentile of a tenth as many
/// particles sits nearer the maximum). With `splash`, its particles count too, each weighing its source
/// particle's mass divided by `perSource` (n_splash). 0 for no particles.
double heightPercentile(const ParticleSet& p, double fraction, const SplashParticles* splash = nullptr,
                        int perSource = 1);

/// The surge front of a dam break along +x [m]: the reach `x_i + r_i` (r_i = H_i / 4, the particle's own
/// radius) of the particle at which the mass reaching at least as far first exceeds `massBeyond` of the
/// fluid's mass, particles taken from the farthest. `massBeyond = 0` gives the farthest particle; a small
/// share (e.g. 0.001) leaves out the few particles that a toe throws ahead of the water, whatever their
/// sizes. For `massBeyond` in [0, 1); a share of 1 or more gives the nearest particle's reach, a negative one
/// the farthest's. 0 for no particles.
double surgeFront(const ParticleSet& p, double massBeyond);

/// Mean density errors of a state, from the densities of its last step.
struct DensityErrorMeans {
  double perParticle = 0.0;     ///< mean over particles of max(0, rho / rho0 - 1) [-]
  double volumeWeighted = 0.0;  ///< the same weighted by rest volume m / rho0: a coarse particle of 27 fine
                                ///< masses counts 27 times [-]
};
/// The mean compression max(0, rho / rho0 - 1), per particle and volume-weighted; zeros for no particles.
DensityErrorMeans densityErrorMeans(const ParticleSet& p, double restDensity);

/// What time steps per particle could save at most in one step (docs/method.md, Time levels). Each particle's
/// own CFL step is `cfl_factor (H_i / 2) / |v_i + dt a_i|`; in an ideal power-of-two multi-rate scheme it
/// steps 2^L_i dt, the longest such step within its own (L_i <= kMaxTimeLevel), and costs 2^-L_i of a
/// particle-step per step of `dt`. The shares are of one step for every particle (1: nothing to gain).
struct TimeStepHeadroom {
  double capped = 1.0;    ///< with every step within dt_max as well
  double uncapped = 1.0;  ///< with the particles' own CFL steps alone
};
/// The deepest level counted: steps 64 times the global one.
constexpr int kMaxTimeLevel = 6;
/// The headroom of state `p` after a step of `dt` (its velocities and accelerations); 1 for no particles. The
/// sums are of powers of two, so exact in any order.
TimeStepHeadroom timeStepHeadroom(const ParticleSet& p, double dt, double cflFactor, double dtMax);

}  // namespace fp::sim
