#pragma once
/// Changing the resolution (docs/method.md, Adaptivity, after Winchenbach et al. 2017 "Infinite continuous
/// adaptivity for incompressible SPH"): particles far heavier than their optimal mass split 1:n on a template
/// turned to the orientation of least density error (Winchenbach & Kolb 2021), particles far lighter merge
/// into neighbours, heavy ones share mass with light neighbours, and support radii follow the new masses over
/// a few steps. Every operation conserves total mass and linear momentum to round-off.

#include <cstdint>
#include <limits>
#include <vector>

#include "sim/boundary_set.h"
#include "sim/neighbor_search.h"
#include "sim/params.h"
#include "sim/particle_set.h"

namespace fp::sim {

/// Counts and errors of the adaptation, accumulated.
struct AdaptivityStats {
  std::uint64_t splits = 0;           ///< particles split
  std::uint64_t children = 0;         ///< particles created by splits
  std::uint64_t merges = 0;           ///< particles removed by merging into neighbours
  std::uint64_t redistributions = 0;  ///< mass shares from a heavy particle to light neighbours
  std::uint64_t splitsBlocked = 0;    ///< splits postponed because every orientation put a child in a wall
  std::uint64_t splitsCompared = 0;   ///< splits where the unrotated template was valid too
  double splitErrorChosen = 0.0;      ///< sum over compared splits of E of the chosen orientation [-]
  double splitErrorUnrotated = 0.0;   ///< sum over compared splits of E of the unrotated template [-]
  double splitErrorRotated = 0.0;     ///< sum over compared splits of E of the chosen rotation, unmoved [-]

  /// 1 - mean E(chosen) / mean E(unrotated): the density error decrease by the orientation choice [-]
  double splitErrorReduction() const {
    return splitErrorUnrotated > 0.0 ? 1.0 - splitErrorChosen / splitErrorUnrotated : 0.0;
  }
  /// 1 - mean E(chosen rotation, children not moved) / mean E(unrotated): the orientation's part [-]
  double orientationErrorReduction() const {
    return splitErrorUnrotated > 0.0 ? 1.0 - splitErrorRotated / splitErrorUnrotated : 0.0;
  }
  /// adds another set of counts
  AdaptivityStats& operator+=(const AdaptivityStats& o);
};

/// What one particle did in the last Adaptivity::adapt() call, for tests and diagnostics: a bit per kind of
/// operation (OpKind) and the number of operations it took part in (at most one by design).
struct ParticleOps {
  std::uint32_t id = 0;    ///< the particle's id (indices change when the step removes particles)
  std::uint8_t kinds = 0;  ///< OpKind bits
  std::uint8_t count = 0;  ///< operations it took part in
};

/// Kinds of adaptivity operations in ParticleOps::kinds.
enum OpKind : std::uint8_t {
  kOpMerged = 1,    ///< gave all its mass away and was removed
  kOpSplit = 2,     ///< split into children and was removed
  kOpShared = 4,    ///< gave part of its mass to neighbours
  kOpReceived = 8,  ///< received mass from a merge or a share
};

/// What one adaptation step may touch.
struct AdaptContext {
  ParticleSet& fluid;                           ///< fluid particles, changed in place
  const NeighborList& fluidNbrs;                ///< fluid neighbours (from the start of the step)
  const NeighborList& boundaryNbrs;             ///< boundary neighbours (from the start of the step)
  const BoundarySet& boundary;                  ///< boundary particles
  const std::vector<ColliderState>& colliders;  ///< current collider poses (children never land in one)
  const SimParams& params;                      ///< thresholds and template settings
  Real mFine;                                   ///< finest mass [kg]
  double time;                                  ///< simulated time, stamped on split children [s]
  std::uint64_t step;                           ///< step index, part of the orientation seed
};

/// Whether Adaptivity::adapt() leaves out, before its serial merges and shares, the donors whose capacity at
/// the start of the step is already too small (on by default; the result is the same either way). Tests
/// switch it off to compare. Returns the setting before.
bool setAdaptivityPrefilter(bool on);

/// Split, merge, share and support blending, with their scratch arrays.
class Adaptivity {
 public:
  /// Runs one adaptation step on particles whose optimal mass `mOpt` is set: merges too-light particles,
  /// splits too-heavy ones (after `split_delay` adaptation steps, or at once when `ignoreDelay`), shares mass
  /// from heavy to light ones. A particle takes part in one operation per step. Returns this step's counts.
  /// The merged and split particles are removed and the children added at the end; without `compact`, the
  /// removed ones stay where they were and kept() lists the others for the caller to keep (the simulation
  /// drops them in the sort its next neighbour search would make anyway).
  AdaptivityStats adapt(const AdaptContext& ctx, bool ignoreDelay, bool compact = true);
  /// the particles the last adapt() kept, ascending, children included; empty when it removed none
  const std::vector<std::uint32_t>& kept() const { return m_keep; }

  /// Moves every support radius towards the one of its mass, 4 r (m / m_fine)^(1/3), over
  /// `support_blend_steps` steps, so that densities do not jump after a split or a merge. Skips particles
  /// flagged kFlagSupportSettled: every call on a particle set must use the same particle radius and mFine,
  /// and whatever changes a mass must clear the flag.
  static void blendSupports(ParticleSet& p, const SimParams& params, Real mFine);

  /// Split error E (docs/method.md, Adaptivity) of placing the children of `o` at `children` (each of
  /// mass m_o / n and, as the split creates them, the parent's support), with the neighbourhood of the
  /// context, of the densities the solver then sees: with temporal blending on (`split_blend_steps` > 0) a
  /// child's density error enters at (1 - splitBlendWeight(0)) of its own [-]. E is a sum of squares: once
  /// its partial sum exceeds `bound` the rest is not evaluated and that partial sum (> bound) is returned,
  /// so a candidate that cannot beat the best so far costs less and is rejected all the same. (An infinite
  /// bound never stops it, whatever the terms.)
  static double splitError(const AdaptContext& ctx, std::size_t o, const std::vector<Vec3>& children,
                           double bound = std::numeric_limits<double>::infinity());
  /// E of the children at `children` as splitError() defines it, with its kernels in double precision, and
  /// its gradient with respect to each child's position in `gradient` [1/m]: what the position refinement
  /// (`split_position_steps`) descends.
  static double splitErrorGradient(const AdaptContext& ctx, std::size_t o, const std::vector<Vec3d>& children,
                                   std::vector<Vec3d>& gradient);

  /// per particle, indexed as the particles were at the start of the last adapt() call: what it did there
  const std::vector<ParticleOps>& lastOperations() const { return m_ops; }
  /// the merge and share donors the last adapt() left out before its serial passes (setAdaptivityPrefilter)
  std::size_t lastDonorsLeftOut() const { return m_leftOut; }

  /// Temporal blending (docs/method.md, Adaptivity, after Winchenbach et al. 2017): weight beta of the
  /// parent's value in a split child `age` solver steps after the split, 0.5 (1 - age / steps) while
  /// age < steps, else 0 [-]
  static Real splitBlendWeight(std::uint32_t age, int steps);
  /// Blends each split child's velocity towards its parent's, the mass-weighted mean velocity of its
  /// siblings (the parent's momentum, carried by the children): v_s += beta (v_parent - v_s). Conserves
  /// momentum. Call before the densities of the step.
  static void blendSplitVelocities(ParticleSet& p, const SimParams& params);
  /// The sorted particles of the step's neighbour search, through which blendSplitDensities() finds every
  /// particle within a parent's support: the grid, the cell ranges of the fluid (in its current order), of
  /// the static boundary particles [0, staticCount) and of the moving ones [staticCount, size), and the
  /// largest fluid support [m].
  struct SortedParticles {
    const UniformGrid& grid;
    const std::vector<std::uint32_t>& fluidCells;
    const std::vector<std::uint32_t>& staticCells;
    const std::vector<std::uint32_t>& kinematicCells;
    Real maxSupport;
  };
  /// Blends each split child's density towards its parent's, evaluated at the siblings' moving centre of
  /// mass with the parent's mass and support over every fluid and boundary particle within the parent's pair
  /// support of it, the siblings left out (rest volumes, boundary terms scaled as in the solver):
  /// rho_s <- (1 - beta) rho_s + beta rho_parent. Call after the densities, with the particles as the step's
  /// search sorted them (nothing is blended when the fluid's cell ranges hold another number of particles).
  static void blendSplitDensities(ParticleSet& p, const SortedParticles& sorted, const BoundarySet& boundary,
                                  const SimParams& params, Real mFine);
  /// Ages every split child by one solver step; a child older than `split_blend_steps` stops blending.
  static void ageSplitChildren(ParticleSet& p, const SimParams& params);

  /// bytes held
  std::size_t memoryBytes() const;

 private:
  struct SplitPlan {
    std::size_t parent = 0;
    int n = 0;
    int chosen = -1;                     // candidate index, -1 when every candidate puts a child in a wall
    Quatd rotation = Quatd::Identity();  // the chosen rotation (refined around the chosen candidate's)
    double errorChosen = 0.0;      // E of the children split: rotated, then moved (split_position_steps)
    double errorRotated = 0.0;     // E of the chosen rotation before the children moved
    double errorUnrotated = -1.0;  // -1 when the unrotated template is not valid
    std::vector<Vec3> children;    // the moved children; empty when they stay on the rotated template
  };
  void planSplit(const AdaptContext& ctx, SplitPlan& plan) const;
  static std::vector<Vec3> childPositions(const AdaptContext& ctx, std::size_t o, int n, const Quatd& rot);
  /// moves up to `amount` of the donor's mass and momentum to its light neighbours; with `all` the donor is
  /// removed once all its mass is given. True for a completed merge (all) or any share (!all).
  bool transferMass(const AdaptContext& ctx, std::size_t donor, double amount, bool all);
  /// the donor's capacity in transferMass() before any lock of this step, its negative terms left out (and
  /// receivers a hair beyond reach counted): an upper bound of its capacity at any later point of the step
  static double capacityBound(const AdaptContext& ctx, std::size_t donor, bool all);
  void note(std::size_t i, OpKind kind) {
    m_ops[i].kinds = std::uint8_t(m_ops[i].kinds | kind);
    ++m_ops[i].count;
  }

  /// what adapt()'s first pass found a particle may take part in (m_kind bits)
  enum MayKind : std::uint8_t { kMayMerge = 1, kMaySplit = 2, kMayShare = 4 };

  std::vector<std::uint8_t> m_locked;
  std::vector<std::uint8_t> m_removed;
  std::vector<ParticleOps> m_ops;
  std::vector<SplitPlan> m_plans;
  std::vector<std::uint32_t> m_keep;
  std::vector<std::uint8_t> m_kind;
  std::vector<std::uint32_t> m_selected;
  std::size_t m_leftOut = 0;
  std::vector<std::pair<Real, std::uint32_t>> m_candidates;
};

}  // namespace fp::sim
