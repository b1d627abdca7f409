#pragma once
/// Divergence-free SPH (Bender & Koschier 2015, 2017) on multi-mass particles: a divergence-free solve on the
/// velocities and a constant-density solve on the predicted positions, both warm-started, with Akinci 2012
/// boundary particles. Written in densities normalised by rho0 and volumes V_j = m_j / rho0, so that the
/// symmetric pair update dv_i = -dt (k_i + k_j) V_j grad W_ij conserves momentum exactly (m_i V_j = m_j V_i).

#include <cstdint>
#include <vector>

#include "sim/boundary_set.h"
#include "sim/neighbor_search.h"
#include "sim/params.h"
#include "sim/particle_set.h"

namespace fp::sim {

/// What one solver needs to see of the simulation state.
struct SolverContext {
  ParticleSet& fluid;                ///< fluid particles (positions, velocities, stiffness updated)
  const BoundarySet& boundary;       ///< boundary particles
  const NeighborList& fluidNbrs;     ///< fluid neighbours of each fluid particle
  const NeighborList& boundaryNbrs;  ///< boundary neighbours of each fluid particle
  const SimParams& params;           ///< parameters
  /// particles held in this step of multi-rate stepping (1: held), or null: they take no part in the
  /// solves, and the means of both solves are over the others
  const std::uint8_t* held = nullptr;
  std::size_t heldCount = 0;  ///< how many are held
};

/// Convergence figures of one solve.
struct SolveResult {
  int iterations = 0;  ///< iterations run
  double error =
      0.0;  ///< final mean error (density: fraction of rho0; divergence: fraction of rho0 per step)
};

/// The neighbour sums of the levels (sim/levels.h) that the density pass gathers on the steps that compute
/// them, from the kernel values it evaluates anyway, so the levels need no kernel pass of their own (issue
/// 13). The levels finish them with the densities they see (after a split child's density blending): omega_i
/// = curl_i / rho_i, nu_i = nuSum_i / (m_i / rho_i W(0, H_i) + weightSum_i). A neighbour's volume is m_j /
/// rho_j at its density before the pass (the pass writes the densities it would read).
struct LevelSums {
  std::vector<Real> curl;       ///< |sum_j m_j (v_j - v_i) x grad W_ij| [kg/(m^3 s)]
  std::vector<Real> nuSum;      ///< sum_j V_j |v_j - v_i| W_ij [m/s]
  std::vector<Real> weightSum;  ///< sum_j V_j W_ij [-]
  std::vector<Real> rhoBefore;  ///< the densities before the pass, during it only [kg/m^3]
  bool filled = false;          ///< set by the density pass, cleared by the levels that use them
  /// bytes held
  std::size_t memoryBytes() const {
    return (curl.capacity() + nuSum.capacity() + weightSum.capacity() + rhoBefore.capacity()) * sizeof(Real);
  }
};

/// The DFSPH pressure solver and the non-pressure forces; owns its scratch arrays.
class DfsphSolver {
 public:
  /// rho_i and the DFSPH factor alpha_i (eq. 11 of Bender & Koschier 2017); returns the mean compression
  /// max(0, rho/rho0 - 1) over particles (a held one adds nothing). With `levels` it also fills the levels'
  /// neighbour sums (resized to the particle count) in the same pass.
  double computeDensityAndFactor(SolverContext& ctx, LevelSums* levels = nullptr);
  /// divergence-free solve (Algorithm 2 of Bender & Koschier 2017) for step size dt
  SolveResult divergenceSolve(SolverContext& ctx, Real dt);
  /// gravity, XSPH viscosity over a step of dtPrevious, laminar viscosity and surface tension (Akinci 2013)
  /// into fluid.a
  void nonPressureForces(SolverContext& ctx, Real dtPrevious);
  /// CFL step: cfl * min_i(2 r_i / |v_i + a_i dt|), clamped to [dt_min, dt_max]; moving boundary particles
  /// count with their velocity and the boundary's 2 r
  Real cflTimeStep(const SolverContext& ctx, Real dtPrevious) const;
  /// constant-density solve (Algorithm 3 of Bender & Koschier 2017) for step size dt
  SolveResult densitySolve(SolverContext& ctx, Real dt);
  /// v_i += dt a_i (the non-pressure acceleration)
  static void integrateVelocities(SolverContext& ctx, Real dt);
  /// Sets the velocity of every particle that the last density pass found caged (its boundary neighbours
  /// alone fill 0.8 of its rest density, its fluid neighbours under half, and they include a moving
  /// collider's particles: water shut in a closing hand, which cannot lower its density by moving; for a
  /// particle the boundary reaches by 0.3, fluid neighbours that the boundary alone caged in the step before
  /// count as boundary) to its boundary neighbours' kernel-weighted velocity: it moves with the cage, and its
  /// factor is zero, so it exerts no stiffness. The momentum this gives is counted in boundaryImpulse(). Sets
  /// kFlagCaged on the particles the boundary alone cages and clears it on the others (but those held in this
  /// step), for the next density pass. Returns the number of caged particles.
  std::size_t carryCaged(SolverContext& ctx);
  /// per particle, what the last density pass found (see carryCaged): 1 caged by the boundary alone, 2 caged
  /// with a cluster that the boundary alone cages (kCagedClusterBoundaryDensity), 0 not caged
  const std::vector<std::uint8_t>& caged() const { return m_caged; }

  /// momentum given to the fluid by boundary particles since the last reset [kg m/s]
  const Vec3d& boundaryImpulse() const { return m_boundaryImpulse; }
  /// sum of m_i times the boundary part of the non-pressure acceleration of the last nonPressureForces [N]
  const Vec3d& boundaryForce() const { return m_boundaryForce; }
  /// sets the accumulated boundary impulse to zero
  void resetBoundaryImpulse() { m_boundaryImpulse.setZero(); }
  /// the DFSPH factors alpha_i of the last density pass [m^2] (0 where its denominator vanishes)
  const std::vector<Real>& factors() const { return m_factor; }
  /// bytes held by scratch arrays
  std::size_t memoryBytes() const;
  /// releases scratch capacity beyond the current particle and pair counts
  void shrinkToFit();

 private:
  template <bool kLevelSums, bool kXsph>
  double densityAndFactor(SolverContext& ctx, LevelSums* levels);
  /// rate of change of the normalised density from the current velocities into m_rate [1/s], with the
  /// cached pair gradients; stiffness(i, rate) sets m_k[i] and returns i's error; returns the sum of errors
  template <class F>
  double densityRatePass(const SolverContext& ctx, F&& stiffness);
  /// resizes a per-pair cache with some room to grow
  static void resizeCache(std::vector<Real>& cache, std::size_t n);
  /// v_i -= dt * sum_j V_j (k_i + k_j) grad W_ij (+ boundary); adds k to `accumulated`; returns boundary
  /// impulse
  Vec3d applyStiffness(SolverContext& ctx, Real dt, std::vector<Real>& accumulated);

  std::vector<Real> m_factor;         // alpha_i [m^2]
  std::vector<Real> m_rate;           // density rate or predicted density (normalised)
  std::vector<Real> m_k;              // stiffness of the current iteration [m^2/s^2] (in the density pass:
                                      // 1 / rho_i before it, for XSPH)
  std::vector<std::uint8_t> m_full;   // 1 where the neighbourhood is full by count (divergence warm start)
  std::vector<std::uint8_t> m_caged;  // see caged()
  std::vector<std::uint32_t> m_cagedList;  // caged now or flagged (kFlagCaged), for carryCaged
  std::vector<Vec3> m_normal;              // surface-tension normals [-]
  std::vector<Real> m_gradF;               // V_j grad W_ij / (x_i - x_j) per fluid pair of this step [1/m^2]
  std::vector<Real> m_gradB;     // the same per boundary pair, with the boundary's scaled volume [1/m^2]
  std::vector<Real> m_viscRate;  // 1 / D_i of the laminar viscosity's damping rates [s]
  static constexpr std::size_t kNoXsph = ~std::size_t(0);
  std::size_t m_xsphSize = kNoXsph;  // particles whose XSPH sum the density pass left in fluid.a
  Vec3d m_boundaryImpulse = Vec3d::Zero();
  Vec3d m_boundaryForce = Vec3d::Zero();
};

}  // namespace fp::sim
