#pragma once
/// Fluid particles as one array per field (structure of arrays), kept sorted by grid cell so that neighbours
/// are close in memory. Every particle has its own mass and support radius (multi-resolution from day one).

#include <cstdint>
#include <vector>

#include "sim/types.h"

namespace fp::sim {

/// Bits of ParticleSet::flags.
enum ParticleFlag : std::uint32_t {
  kFlagSurface = 1u << 0,  ///< on the free surface (adaptivity)
  kFlagSplit = 1u << 1,    ///< created by a split (renderer highlight)
};

/// ParticleSet::parentId of a particle that blends from no parent.
constexpr std::uint32_t kNoParent = ~std::uint32_t(0);

/// Structure of arrays of the fluid particles.
class ParticleSet {
 public:
  std::vector<Vec3> x;            ///< position [m]
  std::vector<Vec3> v;            ///< velocity [m/s]
  std::vector<Vec3> a;            ///< non-pressure acceleration of the current step [m/s^2]
  std::vector<Real> m;            ///< mass [kg]
  std::vector<Real> H;            ///< support radius [m]
  std::vector<Real> rho;          ///< density [kg/m^3]
  std::vector<Real> kappa;        ///< DFSPH density-solve stiffness, kept for warm start [m^2/s^2]
  std::vector<Real> kappaV;       ///< DFSPH divergence-solve stiffness, kept for warm start [m^2/s^2]
  std::vector<Real> splitTime;    ///< simulated time of the split that created the particle, -1 if none [s]
  std::vector<std::uint32_t> id;  ///< stable identifier, survives sorting
  std::vector<std::uint32_t> flags;       ///< ParticleFlag bits
  std::vector<Real> levelPhi;             ///< visible level R_phi in [0, 1] (0 at the surface), adaptivity
  std::vector<Real> levelOmega;           ///< vorticity level R_omega in [1, Rmax] [-]
  std::vector<Real> levelNu;              ///< velocity-difference level R_nu in [1, Rmax] [-]
  std::vector<Real> mOpt;                 ///< optimal (target) mass of the adaptivity [kg]
  std::vector<Real> phi;                  ///< distance to the free surface, capped (adaptivity) [m]
  std::vector<Real> omega;                ///< vorticity magnitude of the last adaptation step [1/s]
  std::vector<Real> nu;                   ///< velocity difference of the last adaptation step [m/s]
  std::vector<std::uint32_t> heavySteps;  ///< consecutive adaptation steps found too heavy (split delay)
  std::vector<std::uint32_t> parentId;    ///< id of the parent a split child blends from, kNoParent if none
  std::vector<std::uint32_t> splitAge;    ///< solver steps since the split that created the particle

  /// number of particles
  std::size_t size() const { return x.size(); }
  /// appends a particle at rest density; returns its index
  std::size_t add(const Vec3& position, const Vec3& velocity, Real mass, Real support, Real restDensity);
  /// removes every particle
  void clear();
  /// reserves room for n particles in every field
  void reserve(std::size_t n);
  /// releases capacity beyond the particle count in every field
  void shrinkToFit();
  /// reorders all fields so that new index k holds old particle order[k]; `order` is a permutation
  void permute(const std::vector<std::uint32_t>& order);
  /// the next unused stable id
  std::uint32_t nextId() const { return m_nextId; }

  /// total mass, summed in double [kg]
  double totalMass() const;
  /// total linear momentum, summed in double [kg m/s]
  Vec3d totalMomentum() const;
  /// bytes held by the particle arrays (capacity)
  std::size_t memoryBytes() const;

 private:
  friend class StateAccess;  // sim/state_io: restores the next id
  template <class F>
  void forEachField(F&& f);
  std::uint32_t m_nextId = 0;
  std::vector<Vec3> m_scratchVec;
  std::vector<Real> m_scratchReal;
  std::vector<std::uint32_t> m_scratchU32;
};

}  // namespace fp::sim
