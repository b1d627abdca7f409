#pragma once
/// The FluidPlaying paper's three levels and the optimal mass (docs/method.md, Levels): the distance to the
/// free surface phi (cone surface detector of Winchenbach et al. 2017, then distance propagated through the
/// neighbours), the vorticity magnitude omega and the velocity difference nu, each mapped through a user
/// interval, combined into m_opt = m_fine + R_phi / (R_omega R_nu) (m_base - m_fine).

#include <vector>

#include "sim/boundary_set.h"
#include "sim/neighbor_search.h"
#include "sim/params.h"
#include "sim/particle_set.h"
#include "sim/scene.h"

namespace fp::sim {

struct LevelSums;

/// s(x) = clamp((x - lo) / (hi - lo), 0, 1); lo < hi
double levelRamp(double x, double lo, double hi);
/// visible level R_phi = s(phi) in [0, 1]: 0 at the surface (finest), 1 deep inside (coarsest)
double visibleLevel(double phi, double lo, double hi);
/// vorticity or velocity-difference level 1 + (rmax - 1) s(x) in [1, rmax]
double refinementLevel(double x, double lo, double hi, double rmax);
/// m_opt = m_fine + R_phi / (R_omega R_nu) (m_base - m_fine) [kg]
double optimalMass(double rPhi, double rOmega, double rNu, double mFine, double mBase);
/// support radius of a particle of mass m: 4 r_fine (m / m_fine)^(1/3), so that particles of every mass keep
/// the same number of neighbours on their own lattice [m]
Real supportForMass(Real m, Real mFine, Real fineRadius);

/// Flags (kFlagSurface) the particles on the free surface: the cone test of Winchenbach et al. 2017 on
/// volume-weighted neighbour directions, boundary particles counting as neighbours. Used by the levels and by
/// the splash post-process. `volume`, when given, holds m / rho of every particle (as the pass would
/// compute).
void detectSurface(ParticleSet& p, const NeighborList& fluidNbrs, const NeighborList& boundaryNbrs,
                   const BoundarySet& boundary, const Real* volume = nullptr);

/// The CFL limit of refinement (cfl_limited_refinement): a particle that vorticity or velocity difference
/// refines keeps a mass at which it allows kCflSpeedMargin times the step of the fine surface at its speed of
/// the levels' step. The margin covers the particles that speed up between that step and their split,
/// levels_period (8) adaptation steps and split_delay (13) steps later: on the propeller at r = 0.0088 m (2
/// s, 2 threads) a margin of 1.1 left interior split children setting the step in 377 of 519 steps, at 0.65
/// of the surface's step on average; 1.5 took 486 steps, with the same particle share, splash and orientation
/// gain (docs/method.md, Levels).
inline constexpr double kCflSpeedMargin = 1.5;
/// Computes the levels of every particle. Owns its scratch arrays.
class LevelEstimator {
 public:
  /// Fills flags (kFlagSurface), phi, omega, nu (zero in the surface mode), levelPhi, levelOmega, levelNu of
  /// `p` and the unsmoothed optimal mass of every particle into `target`, from the neighbour lists and
  /// densities of the current step. `mFine` is the finest mass [kg]. `sums`: the neighbour sums that the
  /// solver's density pass of this step gathered (DfsphSolver::computeDensityAndFactor; used once, then
  /// marked spent), or nullptr, and the levels gather them in a pass of their own.
  void compute(ParticleSet& p, const NeighborList& fluidNbrs, const NeighborList& boundaryNbrs,
               const BoundarySet& boundary, const SimParams& params, AdaptivityMode mode, Real mFine,
               std::vector<Real>& target, LevelSums* sums = nullptr);

  /// bytes held
  std::size_t memoryBytes() const;

 private:
  /// surface flags and the raw (unaveraged) omega and nu, in one pass over the neighbours (volumes: m_volume)
  void surfaceAndRawDynamics(ParticleSet& p, const NeighborList& fluidNbrs, const NeighborList& boundaryNbrs,
                             const BoundarySet& boundary);
  /// phi = 0 on the surface, the cap where unknown; sets the number of distance passes to run
  void startDistance(ParticleSet& p, Real cap, Real hop, int& passes);
  /// min_j (phi_j + |x_ij|) over the neighbours of i, at most `cap` [m]
  static Real distanceAt(const ParticleSet& p, std::size_t i, const NeighborList& fluidNbrs, Real cap);
  /// one Jacobi pass of the distance, with the kernel average of the raw omega and nu when they are given
  /// (then with the volumes m / rho of m_volume); true when some phi changed
  bool distancePass(ParticleSet& p, const NeighborList& fluidNbrs, Real cap, const Real* rawOmega,
                    const Real* rawNu);
  /// distanceAt, and omega_i and nu_i as the kernel average of the raw values, in one pass over the
  /// neighbours
  static Real distanceAndDynamicsAt(ParticleSet& p, std::size_t i, const NeighborList& fluidNbrs, Real cap,
                                    const Real* rawOmega, const Real* rawNu, const Real* volume);

  std::vector<Real> m_phiNext;
  std::vector<Real> m_volume;              // m / rho of each particle, for one computation
  std::vector<std::uint8_t> m_wasSurface;  // phi == 0 before the computation
  std::vector<Real> m_rawOmega;
  std::vector<Real> m_rawNu;
};

}  // namespace fp::sim
