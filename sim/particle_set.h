#pragma once
/// Fluid particles as one array per field (structure of arrays), kept sorted by grid cell so that neighbours
/// are close in memory. Every particle has its own mass and support radius (multi-resolution from day one).

#include <cstdint>
#include <string>
#include <vector>

#include "sim/types.h"

namespace fp::sim {

/// Bits of ParticleSet::flags.
enum ParticleFlag : std::uint32_t {
  kFlagSurface = 1u << 0,  ///< on the free surface (adaptivity)
  kFlagSplit = 1u << 1,    ///< created by a split (renderer highlight)
  /// the support is its mass's own (Adaptivity::blendSupports): whatever changes the mass clears it
  kFlagSupportSettled = 1u << 2,
  /// caged by the boundary alone at the last density solve (DfsphSolver::carryCaged; a particle held by the
  /// time levels keeps it): its fluid neighbours count it as cage
  kFlagCaged = 1u << 3,
};

/// ParticleSet::parentId of a particle that blends from no parent.
constexpr std::uint32_t kNoParent = ~std::uint32_t(0);

/// One line of a memory breakdown (Simulation::memoryBreakdown): bytes held (vector capacity) and the part
/// of them in use (size); the difference is spare capacity.
struct MemoryItem {
  std::string name;       ///< component
  std::size_t bytes = 0;  ///< held [B]
  std::size_t used = 0;   ///< in use [B]
};

/// Appends a vector's capacity and size to a breakdown line.
template <class V>
void countVector(MemoryItem& item, const V& v) {
  item.bytes += v.capacity() * sizeof(typename V::value_type);
  item.used += v.size() * sizeof(typename V::value_type);
}

/// The bytes held by an object whose memoryBreakdown(out) appends its lines (ParticleSet, BoundarySet).
template <class T>
std::size_t heldBytes(const T& object) {
  std::vector<MemoryItem> items;
  object.memoryBreakdown(items);
  std::size_t bytes = 0;
  for (const MemoryItem& item : items)
    bytes += item.bytes;
  return bytes;
}

/// Structure of arrays of the fluid particles. The fields from splitTime on, after flags, serve the
/// adaptivity only: the uniform modes drop them (setAdaptivityFields(false)), which saves 44 B a particle;
/// they are then empty, and the ...Of(i) readers give their neutral values.
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
  /// true when the adaptivity fields (splitTime, levels, mOpt, phi, omega, nu, heavySteps, parentId,
  /// splitAge) are held; the default
  bool hasAdaptivityFields() const { return m_adaptivityFields; }
  /// keeps the adaptivity fields (sized to the particles at their defaults when they were dropped) or drops
  /// them (emptied, their memory released)
  void setAdaptivityFields(bool keep);
  /// split time of particle i, -1 (never split) without adaptivity fields [s]
  Real splitTimeOf(std::size_t i) const { return splitTime.empty() ? Real(-1) : splitTime[i]; }
  /// visible level of particle i, 1 (base resolution) without adaptivity fields
  Real levelPhiOf(std::size_t i) const { return levelPhi.empty() ? Real(1) : levelPhi[i]; }
  /// vorticity level of particle i, 1 without adaptivity fields
  Real levelOmegaOf(std::size_t i) const { return levelOmega.empty() ? Real(1) : levelOmega[i]; }
  /// velocity-difference level of particle i, 1 without adaptivity fields
  Real levelNuOf(std::size_t i) const { return levelNu.empty() ? Real(1) : levelNu[i]; }
  /// split parent of particle i, kNoParent without adaptivity fields
  std::uint32_t parentIdOf(std::size_t i) const { return parentId.empty() ? kNoParent : parentId[i]; }
  /// appends a particle at rest density; returns its index
  std::size_t add(const Vec3& position, const Vec3& velocity, Real mass, Real support, Real restDensity);
  /// removes every particle
  void clear();
  /// reserves room for n particles in every field
  void reserve(std::size_t n);
  /// releases capacity beyond the particle count in every field
  void shrinkToFit();
  /// reorders all fields so that new index k holds old particle order[k]; `order` is a permutation, or the
  /// indices of the particles to keep (the others are dropped)
  void permute(const std::vector<std::uint32_t>& order);
  /// permute() keeping fewer than this many particles (`order.size()`) goes column by column
  /// (permuteByColumns)
  static constexpr std::size_t kColumnTasksBelow = 16384;
  /// retain() moves each field on its own task from this many moves a field on, below on one thread
  static constexpr std::size_t kRetainTasksFrom = 4096;
  /// keeps the particles `keep` (strictly ascending indices) in their order and drops the others: in place,
  /// moving only the particles after the first dropped one, each field on its own task from kRetainTasksFrom
  /// moves a field on (the merges of an adaptation step drop a few particles of thousands: permute() gathered
  /// and copied back every field)
  void retain(const std::vector<std::uint32_t>& keep);
  /// the next unused stable id
  std::uint32_t nextId() const { return m_nextId; }

  /// total mass, summed in double [kg]
  double totalMass() const;
  /// total linear momentum, summed in double [kg m/s]
  Vec3d totalMomentum() const;
  /// bytes held by the particle arrays (capacity)
  std::size_t memoryBytes() const;
  /// appends the particle arrays' lines to a memory breakdown: solver fields, adaptivity fields, sort scratch
  void memoryBreakdown(std::vector<MemoryItem>& out) const;

 private:
  friend class StateAccess;  // sim/state_io: restores the next id
  // every field held: f(field)
  template <class F>
  void forEachField(F&& f);
  template <class F>
  void forEachAdaptivityField(F&& f);
  // permute() of a few thousand particles: every column (a 4-byte field, or a coordinate of a vector field)
  // on its own task
  void permuteByColumns(const std::vector<std::uint32_t>& order);
  std::uint32_t m_nextId = 0;
  bool m_adaptivityFields = true;
  // permute()'s scratch: one float a particle for every field (vector fields go a coordinate at a time)
  std::vector<Real> m_scratch;
};

}  // namespace fp::sim
