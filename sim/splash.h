#pragma once
/// Splash enhancement of the FluidPlaying paper (docs/method.md, Splash): a render-only post-process in which
/// sparse surface particles spawn temporary spray particles on their outward side. Nothing here feeds back
/// into the simulation: the generator reads a const view of the particles and keeps its own neighbour grid.

#include <cstdint>
#include <vector>

#include "sim/boundary_set.h"
#include "sim/neighbor_search.h"
#include "sim/params.h"
#include "sim/particle_set.h"
#include "sim/types.h"

namespace fp::sim {

class Simulation;

/// draw radius of a splash particle as a share of its source particle's radius r_i = H_i / 4 [-]
constexpr Real kSplashRadiusFraction = Real(0.5);

/// The splash of one frame, ordered by source particle index, then by k in [0, n_splash).
struct SplashParticles {
  std::vector<Vec3> x;                ///< positions [m]
  std::vector<Real> radius;           ///< draw radius [m], kSplashRadiusFraction r_i
  std::vector<std::uint32_t> source;  ///< index of the spawning fluid particle in the ParticleSet
  /// number of splash particles
  std::size_t size() const { return x.size(); }
  /// removes every splash particle
  void clear();
};

/// Generates splash particles: a surface particle i (kFlagSurface of detectSurface) with fewer than
/// N_splash fluid neighbours spawns n_splash particles at x_i + alpha r_i d / |d|, d = xhat_i / |xhat_i| +
/// n_r, xhat_i = sum_j x_ij V_j W(x_ij, H_ij) (x_ij = x_i - x_j, V_j = m_j / rho_j; boundary neighbours count
/// with their Akinci volume, as in the density, so a film on a wall sprays away from the wall). alpha is
/// uniform in [alpha_min, alpha_max], n_r uniform in the ball of radius n_r_max. Where the neighbours give no
/// direction (an isolated droplet, or a balanced neighbourhood: xhat ~ 0) the particle's velocity direction
/// stands in for xhat_i / |xhat_i|, and with no velocity either d is n_r alone (a random unit direction when
/// n_r_max is 0). Random numbers come from a counter-based hash of (seed, particle id, frame, k): the spray
/// does not flicker between renders of one frame and is the same for every thread count. Owns its scratch
/// arrays.
class SplashGenerator {
 public:
  /// Splash of the current state, deterministic per particle id and `frame`; empty when
  /// params.splashEnabled is false or n_splash is 0. Builds its own neighbour grid over `domain` (the
  /// simulation's lists may be stale after adaptation); reads p.x, v, m, H, rho, id and the boundary, whose
  /// static part it sorts once and keeps while BoundarySet::staticVersion() holds. The result stays valid
  /// until the next call.
  const SplashParticles& generate(const ParticleSet& p, const BoundarySet& boundary, const SimParams& params,
                                  const Aabb& domain, std::uint64_t frame);
  /// generate() on a simulation's particles, boundary, parameters and domain; on its own neighbour lists,
  /// with no search, where they are those of its current state (Simulation::neighborsCurrent(): the same
  /// pairs, summed in another order)
  const SplashParticles& generate(const Simulation& simulation, std::uint64_t frame);

  /// the result of the last generate()
  const SplashParticles& splash() const { return m_out; }
  /// bytes held by the result and the scratch arrays
  std::size_t memoryBytes() const;

 private:
  void searchNeighbors(const ParticleSet& p, const BoundarySet& boundary, const Aabb& domain);
  /// m_sorted's x, m, H, rho: p's in m_order; flags cleared
  void copyInOrder(const ParticleSet& p);
  /// no splash: switched off, no particle to spawn per spawner, or no fluid
  static bool off(const SimParams& params, std::size_t particles) {
    return !params.splashEnabled || params.splashCount <= 0 || particles == 0;
  }
  /// surface detection and the splash particles, on m_sorted (p in m_order) and lists over it
  const SplashParticles& spawn(const ParticleSet& p, const BoundarySet& boundary, const SimParams& params,
                               std::uint64_t frame, const NeighborList& fluidNbrs,
                               const NeighborList& boundaryNbrs);

  SplashParticles m_out;
  UniformGrid m_grid;
  Aabb m_gridDomain;
  Real m_gridCell = 0;
  NeighborSearch m_search;
  NeighborList m_fluidNbrs;            // over m_sorted
  NeighborList m_boundaryNbrs;         // indices into the caller's boundary
  ParticleSet m_sorted;                // x, m, H, rho, flags of the caller's particles in cell order
  std::vector<std::uint32_t> m_order;  // m_sorted index s <- caller index m_order[s]
  std::vector<std::uint32_t> m_fluidCells;
  // the static boundary sorted by cell, kept while the boundary's staticVersion() and the grid hold
  std::uint64_t m_staticVersion = ~std::uint64_t(0);
  std::vector<std::uint32_t> m_staticOrder;
  std::vector<std::uint32_t> m_staticCells;
  std::vector<Vec3> m_staticX;
  PointBounds m_staticBounds;
  // the kinematic boundary sorted by cell, every call
  std::vector<std::uint32_t> m_kinematicOrder;
  std::vector<std::uint32_t> m_kinematicCells;
  std::vector<Vec3> m_kinematicX;
  std::vector<Vec3> m_outward;         // by caller index: unit outward direction, or zero
  std::vector<std::uint8_t> m_spawns;  // by caller index
  std::vector<std::uint32_t> m_first;  // by caller index: first spawner rank
};

}  // namespace fp::sim
