#pragma once
/// Boundary particles of Akinci et al. 2012 ("Versatile rigid-fluid coupling for incompressible SPH"): one
/// layer of particles sampled on every collider surface, each with a volume psi_b = 1 / sum_k W(x_b - x_k)
/// over the particles of its own collider, so that walls sampled unevenly still push back evenly. A fluid
/// particle of another size sees the wall through the pair support H_ib = (H_i + H_b) / 2; since a plane's
/// kernel sum falls as 1 / H, the volumes are then scaled by H_ib / H_b, which keeps the wall as dense, for
/// every particle size, as the fluid it stands in for (without it coarse particles sink into walls sampled
/// for fine ones). Static colliders' particles come first and are sorted into the grid once; kinematic
/// colliders' particles follow and move with their collider's pose.

#include <cstdint>
#include <vector>

#include "sim/particle_set.h"
#include "sim/scene.h"
#include "sim/types.h"

namespace fp::sim {

/// Current pose and velocity of a collider.
struct ColliderState {
  ColliderDesc desc;                      ///< shape and initial pose
  Vec3d position{0.0, 0.0, 0.0};          ///< current origin [m]
  Quatd orientation = Quatd::Identity();  ///< current rotation local -> world
  Vec3d linearVelocity{0.0, 0.0, 0.0};    ///< [m/s]
  Vec3d angularVelocity{0.0, 0.0, 0.0};   ///< about `position`, world [rad/s]
  std::size_t particleCount = 0;          ///< boundary particles sampled on it
};

/// Structure of arrays of the boundary particles. Static particles never move: they hold no velocity (zero)
/// nor local position, so `v` and `local` cover the kinematic particles only, particle i >= staticCount() at
/// index i - staticCount() (velocity(i) reads any particle's).
class BoundarySet {
 public:
  std::vector<Vec3> x;                  ///< world position [m]
  std::vector<Vec3> v;                  ///< velocity of the kinematic particles, from staticCount() on [m/s]
  std::vector<Real> psi;                ///< Akinci volume [m^3]
  std::vector<Vec3d> local;             ///< position in the collider frame, kinematic particles only [m]
  std::vector<std::uint16_t> collider;  ///< index of the owning collider

  /// Samples every collider with spacing 2r and support 4r, computes the volumes, orders static particles
  /// first.
  void build(const std::vector<ColliderState>& colliders, Real particleRadius);
  /// number of boundary particles
  std::size_t size() const { return x.size(); }
  /// particles [0, staticCount()) never move
  std::size_t staticCount() const { return m_staticCount; }
  /// identifies the static particles as they are: a new value (unique in the process) whenever build() or
  /// permute() changed them, so a reader may keep what it derived from them (a sorted copy) while it holds
  std::uint64_t staticVersion() const { return m_staticVersion; }
  /// velocity of boundary particle i, zero for a static one [m/s]
  Vec3 velocity(std::size_t i) const { return i < m_staticCount ? Vec3::Zero() : v[i - m_staticCount]; }
  /// support radius of every boundary particle [m]
  Real support() const { return m_support; }
  /// factor on psi for a fluid particle of support Hi: the pair support over the boundary's own, H_ib / H_b
  Real volumeScale(Real Hi) const { return Real(0.5) * (Hi + m_support) / m_support; }
  /// moves the kinematic particles to their colliders' current poses and sets their velocities
  void updateKinematic(const std::vector<ColliderState>& colliders);
  /// reorders particles [begin, begin + order.size()): new begin + k holds old begin + order[k]; the range
  /// lies among the static particles or among the kinematic ones
  void permute(std::size_t begin, const std::vector<std::uint32_t>& order);
  /// bytes held
  std::size_t memoryBytes() const;
  /// appends the boundary arrays' lines to a memory breakdown
  void memoryBreakdown(std::vector<MemoryItem>& out) const;

 private:
  std::size_t m_staticCount = 0;
  std::uint64_t m_staticVersion = 0;
  Real m_support = 0;
};

}  // namespace fp::sim
