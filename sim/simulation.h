#pragma once
/// The simulation: fluid and boundary particles, colliders, neighbour search and the DFSPH step, with
/// per-phase timing, conservation bookkeeping and instability detection. Driven from a test in a few lines:
///   fp::sim::Simulation sim(scene); while (sim.time() < 1.0) sim.step();

#include <chrono>
#include <cstdint>
#include <vector>

#include "sim/adaptivity.h"
#include "sim/boundary_set.h"
#include "sim/dfsph_solver.h"
#include "sim/levels.h"
#include "sim/neighbor_search.h"
#include "sim/particle_set.h"
#include "sim/scene.h"

namespace fp::sim {

/// Wall time of the phases of one step [s].
struct PhaseTimes {
  double neighbors = 0;   ///< sorting and neighbour lists
  double density = 0;     ///< densities and DFSPH factors
  double divergence = 0;  ///< divergence-free solve
  double viscosity = 0;   ///< non-pressure forces (gravity, viscosity, surface tension)
  double pressure = 0;    ///< constant-density solve
  double boundaries = 0;  ///< collider poses and kinematic boundary particles
  double integrate = 0;   ///< time step, integration and checks
  double levels = 0;      ///< surface distance, vorticity, velocity difference and optimal masses
  double adaptation = 0;  ///< split, merge, share and support blending
  /// sum of all phases
  double total() const {
    return neighbors + density + divergence + viscosity + pressure + boundaries + integrate + levels +
           adaptation;
  }
  PhaseTimes& operator+=(const PhaseTimes& o);
};

/// Figures of one step.
struct StepStats {
  double dt = 0;                  ///< step size [s]
  int densityIterations = 0;      ///< iterations of the constant-density solve
  int divergenceIterations = 0;   ///< iterations of the divergence-free solve
  double densityError = 0;        ///< mean compression max(0, rho/rho0 - 1) at the start of the step [-]
  double solverDensityError = 0;  ///< mean predicted density error left by the solver [-]
  double fluidNeighbors = 0;      ///< mean fluid neighbours per particle
  double boundaryNeighbors = 0;   ///< mean boundary neighbours per particle
  PhaseTimes times;               ///< wall time by phase
  AdaptivityStats adaptivity;     ///< splits, merges and redistributions of this step
  std::size_t heldParticles = 0;  ///< particles that held their acceleration this step (time_levels = 2)
  double maxSpeed = 0;            ///< speed of the fastest fluid particle after the step's integration [m/s]
  std::size_t cagedParticles =
      0;  ///< particles moved with the boundary that cages them (DfsphSolver::carryCaged)
};

/// Figures accumulated over many steps.
struct RunStats {
  std::uint64_t steps = 0;                 ///< steps taken
  std::uint64_t particleSteps = 0;         ///< sum over steps of the particle count
  std::size_t particlesMax = 0;            ///< largest particle count
  double simTime = 0;                      ///< simulated time [s]
  double densityErrorSum = 0;              ///< sum of StepStats::densityError
  double densityErrorMax = 0;              ///< largest StepStats::densityError
  std::uint64_t densityIterations = 0;     ///< total density iterations
  std::uint64_t divergenceIterations = 0;  ///< total divergence iterations
  double neighborsSum = 0;                 ///< sum of mean (fluid + boundary) neighbours per step
  PhaseTimes times;                        ///< wall time by phase
  AdaptivityStats adaptivity;              ///< splits, merges and redistributions
  std::uint64_t heldParticleSteps = 0;     ///< sum over steps of StepStats::heldParticles
  std::uint64_t level1ParticleSteps = 0;   ///< sum over steps of the particles on time level 1
  double maxSpeed = 0;                     ///< largest StepStats::maxSpeed [m/s]
  std::uint64_t cagedParticleSteps = 0;    ///< sum over steps of StepStats::cagedParticles
  double maxSpeedTime = 0;                 ///< Simulation::time() at the end of the step that reached it [s]
  /// add one step
  void add(const StepStats& s, std::size_t particles);
};

/// A running simulation.
/// Whether a step that split or merged drops the removed particles in the sort by cell of the next search,
/// made at the step's end (on by default), or compacts them in a pass of its own first; the results are the
/// same either way. Tests switch it off to compare. Returns the setting before.
bool setPresortAfterAdaptation(bool on);

class Simulation {
 public:
  /// builds particles and colliders from a scene; throws InputError for an invalid scene
  explicit Simulation(const SceneDesc& scene);

  /// advances by one CFL step; throws InstabilityError naming the step and particle when the state goes bad
  void step();

  /// simulated time [s]
  double time() const { return m_time; }
  /// steps taken
  std::uint64_t stepCount() const { return m_stepCount; }
  /// fluid particles, read-only
  const ParticleSet& particles() const { return m_fluid; }
  /// boundary particles, read-only
  const BoundarySet& boundary() const { return m_boundary; }
  /// colliders with their current poses
  const std::vector<ColliderState>& colliders() const { return m_colliders; }
  /// parameters; the ones marked live in the table may be changed between steps
  SimParams& params() { return m_params; }
  /// parameters
  const SimParams& params() const { return m_params; }
  /// the scene it was built from
  const SceneDesc& scene() const { return m_scene; }
  /// figures of the last step
  const StepStats& lastStep() const { return m_last; }
  /// figures since construction or the last resetRunStats()
  const RunStats& runStats() const { return m_run; }
  /// restarts the accumulation of runStats()
  void resetRunStats() { m_run = RunStats{}; }
  /// momentum given to the fluid by boundaries since construction [kg m/s]
  const Vec3d& boundaryImpulse() const { return m_boundaryImpulse; }
  /// fluid neighbours of each fluid particle at the start of the last step; empty when that step split or
  /// merged particles (see neighborsValid())
  const NeighborList& fluidNeighbors() const { return m_fluidNbrs; }
  /// boundary neighbours of each fluid particle, like fluidNeighbors()
  const NeighborList& boundaryNeighbors() const { return m_boundaryNbrs; }
  /// Sorts the particles and builds both neighbour lists for the current state, the search the next step()
  /// would start with: readers between steps (the splash) get the lists of the current positions, and the
  /// next step searches only the boundary again (its colliders move at its start). The step's results are
  /// the same bit for bit; its neighbour time includes this search. No-op while neighborsCurrent().
  void prepareNeighbors();
  /// true from prepareNeighbors() to the next step(): fluidNeighbors() and boundaryNeighbors() are those of
  /// the current positions, supports and boundary particles, and the particles are in the search's order
  bool neighborsCurrent() const { return m_neighborsCurrent; }
  /// true when fluidNeighbors() and boundaryNeighbors() index the current particles
  bool neighborsValid() const {
    return m_fluidNbrs.offsets.size() == m_fluid.size() + 1 &&
           m_boundaryNbrs.offsets.size() == m_fluid.size() + 1;
  }

  /// Sets the pose and velocity of a driven collider for the coming step (the hand). Throws InputError for a
  /// collider that is not driven.
  void setColliderPose(std::size_t collider, const Vec3d& position, const Quatd& orientation,
                       const Vec3d& linearVelocity, const Vec3d& angularVelocity);

  /// pressure of fluid particle i from the stiffness of both solves of the last step, p = k rho^2 / rho0 [Pa]
  double pressure(std::size_t i) const;
  /// total fluid mass [kg]
  double totalMass() const { return m_fluid.totalMass(); }
  /// total fluid momentum [kg m/s]
  Vec3d totalMomentum() const { return m_fluid.totalMomentum(); }
  /// bytes held by particles, boundaries, grid, neighbour lists and solver scratch (the sum of
  /// memoryBreakdown())
  std::size_t memoryBytes() const;
  /// the bytes held, by component (fp_bench --memory prints it per fluid particle)
  std::vector<MemoryItem> memoryBreakdown() const;
  /// mass of a fluid particle on the initial lattice, the finest mass m_fine [kg]
  Real latticeMass() const { return m_latticeMass; }
  /// the coarsest mass m_base = mass_ratio * m_fine [kg]
  Real baseMass() const { return Real(m_params.massRatio) * m_latticeMass; }
  /// the adaptivity, read-only (its record of the last adaptation step)
  const Adaptivity& adaptivity() const { return m_adaptivity; }
  /// resolution mode
  AdaptivityMode mode() const { return m_mode; }
  /// true when the resolution changes during the run (surface and fluidplaying modes)
  bool adaptive() const {
    return m_mode == AdaptivityMode::Surface || m_mode == AdaptivityMode::FluidPlaying;
  }

 private:
  friend class StateAccess;  // sim/state_io: saves and restores the private state
  void createFluid();
  void coarsenInitialLattice(const std::vector<Eigen::Vector4i>& lattice,
                             const std::vector<Eigen::Vector3i>& counts);
  /// the levels and the smoothed optimal masses; `sums`: the level sums of this step's density pass, or
  /// nullptr
  void computeLevels(bool smooth, LevelSums* sums = nullptr);
  void relax(int steps);
  /// every particle at the velocity createFluid gave it (`initialById`, NaN for none), after the settling
  /// held them still; see the .cpp for particles created during the settling
  void restoreInitialVelocities(const std::vector<Vec3>& initialById);
  AdaptivityStats adaptResolution(bool ignoreDelay, bool compact = true);
  /// sorts the fluid particles by cell and reorders them so (searchFluidNeighbors); with `subset`, only those
  /// particles are kept
  void sortFluid(const std::vector<std::uint32_t>* subset = nullptr);
  void updateColliders();
  void searchNeighbors();
  void searchFluidNeighbors();
  void searchBoundaryNeighbors();
  /// moves the fluid by dt; returns the fastest particle's speed [m/s]
  Real integrateAndCheck(Real dt);
  std::size_t holdCoarse();
  void reactOnHeld(Real dt);
  void restoreHeld(std::vector<Real>& field, const std::vector<Real>& saved) const;
  std::size_t assignTimeLevels(Real dt);

  SceneDesc m_scene;
  SimParams m_params;
  ParticleSet m_fluid;
  BoundarySet m_boundary;
  std::vector<ColliderState> m_colliders;
  UniformGrid m_grid;
  NeighborSearch m_search;
  NeighborList m_fluidNbrs;
  NeighborList m_boundaryNbrs;
  std::vector<std::uint32_t> m_order;
  std::vector<std::uint32_t> m_fluidCells;
  std::vector<std::uint32_t> m_staticCells;
  PointBounds m_staticBounds;       // bounding box of the static boundary particles (they never move)
  CellClearance m_staticClearance;  // their distance bounds per cell of m_grid
  std::vector<std::uint32_t> m_kinematicCells;
  DfsphSolver m_solver;
  AdaptivityMode m_mode = AdaptivityMode::UniformHigh;
  LevelEstimator m_levels;
  LevelSums m_levelSums;  // gathered by the density pass of the steps that compute the levels
  Adaptivity m_adaptivity;
  std::vector<Real> m_target;
  // time levels (time_levels = 2): particles held this step, and their saved fields
  std::vector<std::uint32_t> m_held;
  std::vector<std::uint8_t> m_heldMask;            // 1 for the particles in m_held (held steps)
  NeighborList m_dropScratchFluid;                 // dropNeighbors' other arrays for m_fluidNbrs (held steps)
  NeighborList m_dropScratchBoundary;              // and for m_boundaryNbrs
  std::vector<std::uint8_t> m_timeLevelCandidate;  // assignTimeLevels' candidates
  std::vector<Real> m_heldRho, m_heldKappa, m_heldKappaV;
  std::size_t m_level1 = 0;
  bool m_heldLastStep = false;
  bool m_settling = false;  // relax() runs: updateColliders() holds kinematic and driven colliders still
  // prepareNeighbors(): the lists are those of the current state; the largest support of their search; the
  // wall time of the search, counted in the next step's neighbour time
  bool m_neighborsCurrent = false;
  // the fluid was sorted by cell at the end of the last step (which dropped the particles its adaptation
  // removed so) and has not moved since: the next search skips the sort
  bool m_fluidPresorted = false;
  Real m_searchMaxH = 0;
  double m_preparedSeconds = 0.0;
  NeighborList m_heldNbrs;
  Real m_support = 0;
  Real m_latticeMass = 0;
  Real m_dt = 0;
  double m_time = 0;
  std::uint64_t m_stepCount = 0;
  Vec3d m_boundaryImpulse = Vec3d::Zero();
  StepStats m_last;
  RunStats m_run;
};

}  // namespace fp::sim
