#include "sim/simulation.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>

#include "sim/kernels.h"
#include "sim/parallel.h"
#include "sim/signed_distance.h"
#include "sim/split_templates.h"

namespace fp::sim {

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

/// sum_k W(|x_k|, H) over a cubic lattice of spacing d around the origin, the self term included: the rest
/// density of a lattice of unit masses. Masses are chosen as rho0 / this, so the initial interior is exactly
/// at rest.
double latticeKernelSum(double H, double d) {
  const int reach = int(std::ceil(H / d));
  double sum = 0.0;
  for (int z = -reach; z <= reach; ++z)
    for (int y = -reach; y <= reach; ++y)
      for (int x = -reach; x <= reach; ++x) {
        const double r = d * std::sqrt(double(x * x + y * y + z * z));
        sum += CubicSpline::w(Real(r), Real(H));
      }
  return sum;
}

/// Initial coarse blocks may be this much heavier than their points' optimal masses: below the split
/// threshold, so they are only "heavy" and share mass down gradually, which starts the run near the
/// resolution the adaptation settles at instead of with a thick band of fine particles to merge.
constexpr double kInitialHeaviness = 1.9;
// supports of the initial lattice's level computation over the particles' 4 r (coarsenInitialLattice)
constexpr double kLatticeSupportScale = 1.2;

/// ParticleSet::flags bit of a particle on time level 1: its own CFL allows twice the step, and it holds its
/// acceleration through every other step (docs/method.md, Time levels).
constexpr std::uint32_t kFlagTimeLevel1 = 1u << 16;

/// Rows of `in` filtered into `out`: for k in [0, rows), out's row k holds the entries j of in's row rowOf(k)
/// with keepEntry(j), or none where !keepRow(k). Blocks of rows count what they keep, then write it from
/// their offsets, so the result does not depend on the thread count. `out` is wide, or, with `sameRows`
/// (rowOf(k) == k), in the form of `in`.
template <class RowOf, class KeepRow, class KeepEntry>
void filterRows(const NeighborList& in, std::size_t rows, const RowOf& rowOf, const KeepRow& keepRow,
                const KeepEntry& keepEntry, NeighborList& out, bool sameRows = false) {
  const bool narrow = sameRows && in.narrow;
  using Range = tbb::blocked_range<std::size_t>;
  constexpr std::size_t kBlock = 2048;
  const std::size_t blocks = (rows + kBlock - 1) / kBlock;
  std::vector<std::uint32_t> first(blocks + 1, 0);
  parallelFor(Range(0, blocks, 1), [&](const Range& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::uint32_t count = 0;
      for (std::size_t k = b * kBlock; k < std::min(rows, (b + 1) * kBlock); ++k) {
        if (!keepRow(k))
          continue;
        const std::size_t i = rowOf(k);
        for (std::uint32_t q = in.offsets[i]; q < in.offsets[i + 1]; ++q)
          count += keepEntry(in.neighbor(i, q)) ? 1 : 0;
      }
      first[b + 1] = count;
    }
  });
  for (std::size_t b = 0; b < blocks; ++b)
    first[b + 1] += first[b];
  out.offsets.resize(rows + 1);
  out.narrow = narrow;
  if (narrow)
    out.deltas.resize(first[blocks]);
  else
    out.indices.resize(first[blocks]);
  parallelFor(Range(0, blocks, 1), [&](const Range& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::uint32_t write = first[b];
      for (std::size_t k = b * kBlock; k < std::min(rows, (b + 1) * kBlock); ++k) {
        out.offsets[k] = write;
        if (!keepRow(k))
          continue;
        const std::size_t i = rowOf(k);
        for (std::uint32_t q = in.offsets[i]; q < in.offsets[i + 1]; ++q) {
          const std::uint32_t j = in.neighbor(i, q);
          if (!keepEntry(j))
            continue;
          if (narrow)
            out.deltas[write++] = in.deltas[q];
          else
            out.indices[write++] = j;
        }
      }
    }
  });
  out.offsets[rows] = first[blocks];
}

/// Empties the rows of the particles marked in `held` in `list`: they take no part in this step's solves. The
/// rows are filtered into `scratch`, which is swapped in (the old arrays are the next call's scratch).
void dropNeighbors(NeighborList& list, const std::vector<std::uint8_t>& held, NeighborList& scratch) {
  filterRows(
      list, list.offsets.size() - 1, [](std::size_t k) { return k; }, [&](std::size_t k) { return !held[k]; },
      [](std::uint32_t) { return true; }, scratch, true);
  std::swap(list.offsets, scratch.offsets);
  std::swap(list.indices, scratch.indices);
  std::swap(list.deltas, scratch.deltas);
  std::swap(list.narrow, scratch.narrow);
}

/// Releases an object's spare capacity: a copy's vectors hold what they contain, no more.
template <class T>
void fitCapacity(T& object) {
  T fitted = object;
  object = std::move(fitted);
}

std::string formatVec(const Vec3& v) {
  std::ostringstream s;
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

}  // namespace

PhaseTimes& PhaseTimes::operator+=(const PhaseTimes& o) {
  neighbors += o.neighbors;
  density += o.density;
  divergence += o.divergence;
  viscosity += o.viscosity;
  pressure += o.pressure;
  boundaries += o.boundaries;
  integrate += o.integrate;
  levels += o.levels;
  adaptation += o.adaptation;
  return *this;
}

void RunStats::add(const StepStats& s, std::size_t particles) {
  ++steps;
  particleSteps += particles;
  particlesMax = std::max(particlesMax, particles);
  simTime += s.dt;
  maxSpeed = std::max(maxSpeed, s.maxSpeed);
  cagedParticleSteps += s.cagedParticles;
  densityErrorSum += s.densityError;
  densityErrorMax = std::max(densityErrorMax, s.densityError);
  densityIterations += std::uint64_t(s.densityIterations);
  divergenceIterations += std::uint64_t(s.divergenceIterations);
  neighborsSum += s.fluidNeighbors + s.boundaryNeighbors;
  heldParticleSteps += s.heldParticles;
  times += s.times;
  adaptivity += s.adaptivity;
}

Simulation::Simulation(const SceneDesc& scene) : m_scene(scene), m_params(scene.params), m_mode(scene.mode) {
  const std::string invalid = ParamTable::validate(m_params);
  if (!invalid.empty())
    throw InputError(scene.name + ": " + invalid);
  if (m_scene.domain.isEmpty() || (m_scene.domain.sizes().array() <= 0.0).any()) {
    throw InputError(scene.name + ": the domain is empty");
  }
  if (m_scene.colliders.size() > std::numeric_limits<std::uint16_t>::max()) {
    throw InputError(scene.name + ": too many colliders");
  }
  // A scene built in code can carry garbage (an Eigen vector initialised with `{}` is not zeroed): a
  // non-finite number would surface steps later as an instability far from its cause.
  for (std::size_t b = 0; b < m_scene.fluid.size(); ++b) {
    const FluidBlock& block = m_scene.fluid[b];
    if (!block.box.min().allFinite() || !block.box.max().allFinite() || !block.velocity.allFinite()) {
      throw InputError(scene.name + ": fluid block " + std::to_string(b) +
                       " has a non-finite box or velocity");
    }
  }
  for (const ColliderDesc& c : m_scene.colliders) {
    const bool finite = c.halfExtents.allFinite() && std::isfinite(c.radius) && std::isfinite(c.halfLength) &&
                        std::isfinite(c.headroom) && c.position.allFinite() &&
                        c.orientation.coeffs().allFinite() && c.linearVelocity.allFinite() &&
                        c.angularVelocity.allFinite();
    if (!finite) {
      throw InputError(scene.name + ": collider '" + c.name + "' has a non-finite size, pose or velocity");
    }
  }
  const Real r = Real(m_params.particleRadius);
  m_support = Real(4) * r;
  for (const ColliderDesc& c : m_scene.colliders) {
    ColliderState s;
    s.desc = c;
    s.position = c.position;
    s.orientation = c.orientation.normalized();
    s.linearVelocity = c.linearVelocity;
    s.angularVelocity = c.angularVelocity;
    m_colliders.push_back(s);
  }
  m_boundary.build(m_colliders, r);
  for (std::uint16_t c : m_boundary.collider)
    ++m_colliders[c].particleCount;

  m_grid.setup(m_scene.domain, m_support);
  {
    // static boundary particles are sorted into the grid once, with scratch released right after (in the
    // small scenes they outnumber the fluid particles five times: the grid's keys and the order would keep
    // room for them for the whole run)
    UniformGrid once = m_grid;
    std::vector<std::uint32_t> order;
    once.sort(m_boundary.x.data(), m_boundary.staticCount(), order, m_staticCells);
    m_boundary.permute(0, order);
  }
  m_staticBounds = pointBounds(m_boundary.x.data(), m_boundary.staticCount());

  // the uniform modes never split, merge nor estimate levels: their particles hold no adaptivity fields
  m_fluid.setAdaptivityFields(adaptive());
  // The adaptive modes start from the coarsened lattice (createFluid); the band between fine and coarse is
  // filled in by the first adaptation steps, gradually, as during the run. (Settling it before time starts,
  // with supports set at once, left density errors of several percent.)
  createFluid();
  {
    // the walls' clearance, looked at as far as the coarsest particle's pair support with them reaches
    Real maxH = m_support;
    for (Real h : m_fluid.H)
      maxH = std::max(maxH, h);
    m_staticClearance.build(m_grid, m_boundary.x.data(), m_boundary.staticCount(),
                            Real(0.5) * (maxH + m_boundary.support()));
  }
  m_dt = Real(m_params.dtMax);
  // The split templates are built once per process on first use (0.1-0.3 s): here, not in the first step
  // that splits, whose adaptation time it would otherwise swell (0.2 ms a step over a 1 s hand-tank run).
  if (adaptive())
    SplitTemplates::get();
  relax(m_params.initialRelaxation);
  // The modes with coarse particles searched the whole fine lattice once (coarsenInitialLattice), up to
  // seven times as many particles as they keep: every buffer sized for it would stay as spare memory for the
  // whole run (the hand tank's sort keys, levels, search and adaptivity scratch held 200 B a particle of it).
  m_fluid.shrinkToFit();
  m_solver.shrinkToFit();
  fitCapacity(m_fluidNbrs);
  fitCapacity(m_boundaryNbrs);
  fitCapacity(m_grid);
  fitCapacity(m_search);
  fitCapacity(m_levels);
  fitCapacity(m_adaptivity);
  for (std::vector<std::uint32_t>* v : {&m_order, &m_fluidCells, &m_kinematicCells})
    v->shrink_to_fit();
  m_target.shrink_to_fit();
}

void Simulation::relax(int steps) {
  // Damped settling (velocities zeroed after every step, colliders held still at their t = 0 pose), in every
  // mode, so that every mode starts from water at rest under its own weight. A coarsened lattice is not at
  // rest where fine and coarse particles meet, nor at walls, which coarse particles keep farther from:
  // without it the adaptive modes start with a slosh of their own. A lattice of fine particles holds no
  // pressure yet: a dam-break column unsettled stands still for some 30 ms while gravity compresses it, and
  // its surge front then trailed the settled adaptive modes' by up to 8 %
  // (AdaptivePhysicsTest.DamBreakSurgeFrontFollowsUniformHigh). Time, counters and impulses start afresh;
  // the particles then take back the velocities their fluid blocks gave them.
  if (steps > 0) {
    const bool moving = std::any_of(m_scene.fluid.begin(), m_scene.fluid.end(),
                                    [](const FluidBlock& b) { return !b.velocity.isZero(0.0); });
    // by particle id: the velocity createFluid gave it (NaN for ids it did not create)
    std::vector<Vec3> initialById;
    if (moving) {
      initialById.assign(m_fluid.nextId(), Vec3::Constant(std::numeric_limits<Real>::quiet_NaN()));
      for (std::size_t i = 0; i < m_fluid.size(); ++i)
        initialById[m_fluid.id[i]] = m_fluid.v[i];
    }
    std::fill(m_fluid.v.begin(), m_fluid.v.end(), Vec3::Zero());
    m_settling = true;  // updateColliders() holds every moving collider still
    for (int k = 0; k < steps; ++k) {
      step();
      m_time = 0.0;
      std::fill(m_fluid.v.begin(), m_fluid.v.end(), Vec3::Zero());
    }
    m_settling = false;
    // driven colliders (the hand) had no velocity but their scene's before anything set one from outside
    for (ColliderState& c : m_colliders) {
      if (c.desc.driven) {
        c.linearVelocity = c.desc.linearVelocity;
        c.angularVelocity = c.desc.angularVelocity;
      }
    }
    updateColliders();
    if (moving)
      restoreInitialVelocities(initialById);
  }
  std::fill(m_fluid.splitTime.begin(), m_fluid.splitTime.end(), Real(-1));
  std::fill(m_fluid.parentId.begin(), m_fluid.parentId.end(), kNoParent);
  for (std::uint32_t& f : m_fluid.flags)
    f &= ~kFlagTimeLevel1;
  m_heldLastStep = false;
  for (std::uint32_t& f : m_fluid.flags)
    f &= ~std::uint32_t(kFlagSplit);
  m_time = 0.0;
  m_stepCount = 0;
  m_dt = Real(m_params.dtMax);
  m_boundaryImpulse.setZero();
  m_last = StepStats{};
  m_run = RunStats{};
  m_preparedSeconds = 0.0;  // (the settling's last sort is not the first step's)
}

void Simulation::restoreInitialVelocities(const std::vector<Vec3>& initialById) {
  const auto initial = [&](std::uint32_t id, Vec3& v) {
    if (id >= initialById.size() || !initialById[id].allFinite())
      return false;
    v = initialById[id];
    return true;
  };
  // A particle that existed before the settling takes its own velocity back (the uniform modes keep every
  // id; a merge keeps the receiver's); a child split during the settling takes its parent's while it still
  // links to it (split_blend_steps > 0, for that many steps; by default children keep no link). Any other
  // takes the velocity of the block it lies deepest in, or of the nearest one outside all (the first of
  // equals): blocks that touch share a face, where a distance alone cannot tell them apart.
  parallelFor(tbb::blocked_range<std::size_t>(0, m_fluid.size(), 4096),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t i = r.begin(); i < r.end(); ++i) {
                  Vec3& v = m_fluid.v[i];
                  if (initial(m_fluid.id[i], v) || initial(m_fluid.parentIdOf(i), v))
                    continue;
                  const Vec3d x = m_fluid.x[i].cast<double>();
                  double best = std::numeric_limits<double>::infinity();  // less is better
                  Vec3d chosen = Vec3d::Zero();
                  for (const FluidBlock& b : m_scene.fluid) {
                    // inside: minus the depth (distance to the nearest face); outside: the distance
                    const double depth = std::min((x - b.box.min()).minCoeff(), (b.box.max() - x).minCoeff());
                    const double score = depth >= 0.0 ? -depth : std::sqrt(b.box.squaredExteriorDistance(x));
                    if (score < best) {
                      best = score;
                      chosen = b.velocity;
                    }
                  }
                  v = chosen.cast<Real>();
                }
              });
}

void Simulation::createFluid() {
  const double r = m_params.particleRadius;
  const double d = 2.0 * r;
  const double rho0 = m_params.restDensity;
  // lattice_density < 1 gives every particle that share of a rest-density lattice's mass (the reference
  // library's 0.8): the block then starts under-dense and settles to that share of its volume
  m_latticeMass = Real(m_params.latticeDensity * rho0 / latticeKernelSum(4.0 * r, d));
  // Every mode starts from the same lattice of finest particles, so every mode holds the same water; the
  // modes with coarse particles then merge blocks of it (coarsenInitialLattice).
  std::vector<Eigen::Vector4i> lattice;  // fluid block and lattice coordinates of each particle, by id
  std::vector<Eigen::Vector3i> counts;   // lattice points a side of each fluid block
  for (std::size_t b = 0; b < m_scene.fluid.size(); ++b) {
    const FluidBlock& block = m_scene.fluid[b];
    const std::size_t before = m_fluid.size();
    const Vec3d extent = block.box.sizes();
    Eigen::Vector3i count;
    Vec3d start;
    for (int k = 0; k < 3; ++k) {
      // round(extent / d) - 1 particles a side, the rule of the reference library (SPlisHSPlasH), so the
      // standard dam break has the same 47^3 (r = 0.0105) or 19^3 (r = 0.025) particles
      count[k] = std::max(0, int(std::lround(extent[k] / d)) - 1);
      // centre the lattice in the block
      start[k] = block.box.min()[k] + 0.5 * (extent[k] - count[k] * d) + 0.5 * d;
    }
    m_fluid.reserve(m_fluid.size() + std::size_t(count.prod()));
    counts.push_back(count);
    for (int z = 0; z < count.z(); ++z)
      for (int y = 0; y < count.y(); ++y)
        for (int x = 0; x < count.x(); ++x) {
          const Vec3d p = start + d * Vec3d(x, y, z);
          bool blocked = false;
          for (const ColliderDesc& c : m_scene.colliders) {
            // A single layer of Akinci boundary particles holds the fluid about 2.2 r away: a particle at r
            // from a flat wall starts 55% compressed, one at 2r still 6%, and the pressure solve then needs
            // hundreds of iterations. Lattice points closer than 2.2 r to a collider are left out.
            if (signedDistance(c, p) < 1.1 * d) {
              blocked = true;
              break;
            }
          }
          if (!blocked) {
            m_fluid.add(p.cast<Real>(), block.velocity.cast<Real>(), m_latticeMass, m_support, Real(rho0));
            lattice.emplace_back(int(b), x, y, z);
          }
        }
    if (m_fluid.size() == before) {
      throw InputError(m_scene.name + ": fluid block " + std::to_string(b) +
                       " holds no particle (smaller than two spacings, or inside a collider)");
    }
  }
  for (std::size_t i = 0; i < m_fluid.size(); ++i) {
    if (!m_scene.domain.contains(m_fluid.x[i].cast<double>())) {
      throw InputError(m_scene.name + ": fluid particle at " + formatVec(m_fluid.x[i]) +
                       " lies outside the domain");
    }
  }
  if (m_mode != AdaptivityMode::UniformHigh)
    coarsenInitialLattice(lattice, counts);
}

void Simulation::coarsenInitialLattice(const std::vector<Eigen::Vector4i>& lattice,
                                       const std::vector<Eigen::Vector3i>& counts) {
  // Cubic blocks of e^3 lattice points become one particle at their centre of mass: on a lattice of such
  // blocks this reproduces the rest density exactly (the adaptive modes' non-cubic blocks below, nearly).
  // Uniform-low merges every block of the largest edge (e^3 <= mass ratio), partial blocks at the borders
  // included. The adaptive modes merge, largest edge first, the full blocks whose every point may be that
  // coarse (block mass at most kInitialHeaviness times each point's optimal mass), so they start graded from
  // fine at the surface to coarse deep down, with no burst of merges at the first step.
  const std::size_t n = m_fluid.size();
  const int maxEdge = std::max(1, int(std::cbrt(m_params.massRatio + 1e-6)));
  std::vector<Real> target(n, baseMass());
  if (adaptive()) {
    // The lattice keeps 2.2-4.2 r from walls (createFluid), the support is 4 r: a layer at the far end of
    // that gap finds no boundary particle in its support and the cone test takes it for a free surface, so
    // the layers lining the hand tank's z walls and its floor stayed fine (4,385 particles at the start at
    // r = 5 mm; 3,524 now). The lattice's levels are computed with supports kLatticeSupportScale wider,
    // which reach the wall across the largest gap; the steps that follow use the particles' own.
    for (Real& h : m_fluid.H)
      h = Real(kLatticeSupportScale) * m_support;
    searchNeighbors();
    SolverContext ctx{m_fluid, m_boundary, m_fluidNbrs, m_boundaryNbrs, m_params};
    m_solver.computeDensityAndFactor(ctx);
    computeLevels(false);
    for (std::size_t i = 0; i < n; ++i)
      target[m_fluid.id[i]] = m_target[i];  // ids are the creation order, which indexes `lattice`
    for (Real& h : m_fluid.H)
      h = m_support;
  }
  constexpr std::int32_t kNone = -1;
  std::vector<std::int32_t> groupOf(n, kNone);  // by id
  std::int32_t groups = 0;
  // block shapes, largest first: the cubes of every edge down to 2, then (adaptive modes) the 2 x 2 x 1 and
  // 2 x 1 x 1 blocks, which give the points whose optimal mass lies between 1 and 4.2 fine masses (the band
  // between the fine surface and the coarse interior) particles of 2 and 4 of them instead of leaving them
  // fine: the propeller started with 2,520 particles where the adaptation settles at 2,100-2,200
  std::vector<Eigen::Vector3i> shapes;
  for (int e = maxEdge; e >= 2; --e)
    shapes.emplace_back(e, e, e);
  if (adaptive() && maxEdge >= 2) {
    // halves and quarters of the 2-cubes, on their grid (blocks of other shapes, 3 x 3 x 2 and 3 x 2 x 2,
    // cut the 2-cubes' grid and left more particles: 2,553)
    shapes.emplace_back(2, 2, 1);
    shapes.emplace_back(2, 1, 1);
  }
  for (const Eigen::Vector3i& e : shapes) {
    std::vector<std::size_t> first(counts.size() + 1, 0);
    for (std::size_t b = 0; b < counts.size(); ++b) {
      const Eigen::Vector3i blocks = (counts[b].array() + e.array() - 1) / e.array();
      first[b + 1] = first[b] + std::size_t(blocks.prod());
    }
    auto keyOf = [&](const Eigen::Vector4i& l) {
      const Eigen::Vector3i blocks = (counts[std::size_t(l[0])].array() + e.array() - 1) / e.array();
      return first[std::size_t(l[0])] +
             std::size_t(((l[3] / e.z()) * blocks.y() + l[2] / e.y()) * blocks.x() + l[1] / e.x());
    };
    std::vector<std::uint32_t> members(first.back(), 0);
    std::vector<std::uint8_t> ok(first.back(), 1);
    const int volume = e.prod();
    const Real blockMass = Real(volume) * m_latticeMass;
    for (std::size_t id = 0; id < n; ++id) {
      const std::size_t key = keyOf(lattice[id]);
      ++members[key];
      if (groupOf[id] != kNone || blockMass > Real(kInitialHeaviness) * target[id])
        ok[key] = 0;
    }
    std::vector<std::int32_t> groupOfKey(first.back(), kNone);
    for (std::size_t key = 0; key < members.size(); ++key) {
      // Blocks cut by a wall (the lattice keeps 2.2 r from colliders) merge too when at least half full:
      // otherwise a slab of fine particles three layers thick would line every wall.
      const bool fullEnough = 2 * members[key] >= std::uint32_t(volume);
      if (ok[key] && members[key] > 1 && (fullEnough || !adaptive()))
        groupOfKey[key] = groups++;
    }
    for (std::size_t id = 0; id < n; ++id) {
      if (groupOf[id] == kNone)
        groupOf[id] = groupOfKey[keyOf(lattice[id])];
    }
    if (!adaptive())
      break;
  }
  struct Sum {
    double m = 0.0;
    Vec3d mx = Vec3d::Zero();
    Vec3d mv = Vec3d::Zero();
  };
  std::vector<Sum> sums(static_cast<std::size_t>(groups));
  ParticleSet out;
  out.setAdaptivityFields(m_fluid.hasAdaptivityFields());
  out.reserve(m_fluid.size());
  const Real rho0 = Real(m_params.restDensity);
  for (std::size_t i = 0; i < m_fluid.size(); ++i) {
    const std::int32_t group = groupOf[m_fluid.id[i]];
    if (group == kNone) {
      out.add(m_fluid.x[i], m_fluid.v[i], m_fluid.m[i], m_fluid.H[i], rho0);
      continue;
    }
    Sum& sum = sums[std::size_t(group)];
    sum.m += double(m_fluid.m[i]);
    sum.mx += double(m_fluid.m[i]) * m_fluid.x[i].cast<double>();
    sum.mv += double(m_fluid.m[i]) * m_fluid.v[i].cast<double>();
  }
  const Real r = Real(m_params.particleRadius);
  for (const Sum& sum : sums) {
    if (sum.m <= 0.0)
      continue;
    const Real m = Real(sum.m);
    out.add((sum.mx / sum.m).cast<Real>(), (sum.mv / sum.m).cast<Real>(), m,
            supportForMass(m, m_latticeMass, r), rho0);
  }
  m_fluid = std::move(out);
}

void Simulation::computeLevels(bool smooth, LevelSums* sums) {
  m_levels.compute(m_fluid, m_fluidNbrs, m_boundaryNbrs, m_boundary, m_params, m_mode, m_latticeMass,
                   m_target, sums);
  const Real mFine = m_latticeMass;
  const Real mBase = baseMass();
  // levels computed every k solver steps move the target as far as k steps of smoothing would
  const int k = std::max(1, m_params.adaptationPeriod) * std::max(1, m_params.levelsPeriod);
  const Real gamma = smooth ? Real(1.0 - std::pow(1.0 - m_params.massSmoothing, k)) : Real(1);
  parallelFor(tbb::blocked_range<std::size_t>(0, m_fluid.size(), 4096),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t i = r.begin(); i < r.end(); ++i) {
                  const Real m = m_fluid.mOpt[i] + gamma * (m_target[i] - m_fluid.mOpt[i]);
                  m_fluid.mOpt[i] = std::clamp(m, mFine, std::max(mFine, mBase));
                }
              });
}

namespace {
std::atomic<bool>& presortSetting() {
  static std::atomic<bool> on(true);
  return on;
}
}  // namespace

bool setPresortAfterAdaptation(bool on) {
  return presortSetting().exchange(on);
}

AdaptivityStats Simulation::adaptResolution(bool ignoreDelay, bool compact) {
  const AdaptContext ctx{m_fluid,  m_fluidNbrs,   m_boundaryNbrs, m_boundary, m_colliders,
                         m_params, m_latticeMass, m_time,         m_stepCount};
  return m_adaptivity.adapt(ctx, ignoreDelay, compact);
}

void Simulation::setColliderPose(std::size_t collider, const Vec3d& position, const Quatd& orientation,
                                 const Vec3d& linearVelocity, const Vec3d& angularVelocity) {
  if (collider >= m_colliders.size() || !m_colliders[collider].desc.driven) {
    throw InputError("collider " + std::to_string(collider) + " is not a driven collider");
  }
  ColliderState& c = m_colliders[collider];
  c.position = position;
  c.orientation = orientation.normalized();
  c.linearVelocity = linearVelocity;
  c.angularVelocity = angularVelocity;
}

void Simulation::updateColliders() {
  for (ColliderState& c : m_colliders) {
    const ColliderDesc& d = c.desc;
    if (d.driven && m_settling) {
      c.linearVelocity.setZero();
      c.angularVelocity.setZero();
    }
    if (d.driven || !d.kinematic())
      continue;
    // constant velocities: the pose is a closed-form function of time, so no drift accumulates
    const double angle = d.angularVelocity.norm() * m_time;
    const Quatd spin =
        angle > 0.0 ? Quatd(Eigen::AngleAxisd(angle, d.angularVelocity.normalized())) : Quatd::Identity();
    c.orientation = (spin * d.orientation).normalized();
    c.position = d.position + d.linearVelocity * m_time;
    // held still while the start settles (relax): at its start pose and at rest, not stirring the water
    c.linearVelocity = m_settling ? Vec3d::Zero() : d.linearVelocity;
    c.angularVelocity = m_settling ? Vec3d::Zero() : d.angularVelocity;
  }
  if (m_boundary.size() > m_boundary.staticCount())
    m_boundary.updateKinematic(m_colliders);
}

void Simulation::searchNeighbors() {
  searchFluidNeighbors();
  searchBoundaryNeighbors();
}

void Simulation::prepareNeighbors() {
  if (m_neighborsCurrent)
    return;
  const auto t0 = Clock::now();
  searchNeighbors();
  m_preparedSeconds += seconds(t0, Clock::now());
  m_neighborsCurrent = true;
}

void Simulation::sortFluid(const std::vector<std::uint32_t>* subset) {
  // counting sort by cell, then physically reorder so neighbours are close in memory
  const std::size_t n = subset ? subset->size() : m_fluid.size();
  m_grid.sort(m_fluid.x.data(), n, m_order, m_fluidCells, subset ? subset->data() : nullptr);
  m_fluid.permute(m_order);
}

void Simulation::searchFluidNeighbors() {
  // (the cells' header holds the count of points sorted: a guard against particles added since)
  if (!m_fluidPresorted || m_fluidCells.empty() || m_fluidCells[0] != m_fluid.size())
    sortFluid();
  m_fluidPresorted = false;
  using Range = tbb::blocked_range<std::size_t>;
  using MinMax = std::pair<Real, Real>;
  const MinMax hRange = parallelReduce(
      Range(0, m_fluid.size(), 4096), MinMax(std::numeric_limits<Real>::max(), Real(0)),
      [&](const Range& r, MinMax acc) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          acc.first = std::min(acc.first, m_fluid.H[i]);
          acc.second = std::max(acc.second, m_fluid.H[i]);
        }
        return acc;
      },
      [](MinMax a, MinMax b) { return MinMax(std::min(a.first, b.first), std::max(a.second, b.second)); });
  const Real maxH = hRange.second;
  m_searchMaxH = maxH;

  GridPoints fluidSrc{m_fluid.x.data(), m_fluid.H.data(), 0, &m_fluidCells, 0};
  if (hRange.first < maxH)  // mixed sizes: each particle searches only as far as its own support
    m_search.buildSymmetric(m_grid, m_fluid.x, m_fluid.H, m_fluidCells, maxH, m_fluidNbrs, ListForm::kNarrow);
  else
    m_search.build(m_grid, m_fluid.x, m_fluid.H, {fluidSrc}, 0, maxH, m_fluidNbrs, ListForm::kNarrow);
}

void Simulation::searchBoundaryNeighbors() {
  // kinematic boundary particles: sorted like the fluid (the static ones were sorted once, at the start)
  const std::size_t nStatic = m_boundary.staticCount();
  const std::size_t nKinematic = m_boundary.size() - nStatic;
  if (nKinematic > 0) {
    m_grid.sort(m_boundary.x.data() + nStatic, nKinematic, m_order, m_kinematicCells);
    m_boundary.permute(nStatic, m_order);
  }
  const std::vector<GridPoints> walls =
      wallSources(m_boundary.support(), m_boundary.x.data(), nStatic, m_staticCells, &m_staticBounds,
                  &m_staticClearance, m_boundary.x.data() + nStatic, nKinematic, m_kinematicCells);
  m_search.build(m_grid, m_fluid.x, m_fluid.H, walls, -1, m_searchMaxH, m_boundaryNbrs);
}

Real Simulation::integrateAndCheck(Real dt) {
  const std::size_t n = m_fluid.size();
  const Real maxSpeed2 = Real(m_params.maxSpeed * m_params.maxSpeed);
  const Vec3 lo = m_scene.domain.min().cast<Real>();
  const Vec3 hi = m_scene.domain.max().cast<Real>();
  // advance, find the first bad particle (lowest index, so the report is deterministic) and the largest
  // squared speed (a maximum, whatever the split)
  struct Found {
    std::size_t first;
    Real speed2;
  };
  const Found found = parallelReduce(
      tbb::blocked_range<std::size_t>(0, n, 1024), Found{n, Real(0)},
      [&](const tbb::blocked_range<std::size_t>& r, Found f) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          m_fluid.x[i] += dt * m_fluid.v[i];
          const Vec3& x = m_fluid.x[i];
          const Vec3& v = m_fluid.v[i];
          const Real speed2 = v.squaredNorm();
          const bool ok = x.allFinite() && v.allFinite() && speed2 <= maxSpeed2 &&
                          (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
          if (!ok && i < f.first)
            f.first = i;
          if (ok)
            f.speed2 = std::max(f.speed2, speed2);
        }
        return f;
      },
      [](const Found& a, const Found& b) {
        return Found{std::min(a.first, b.first), std::max(a.speed2, b.speed2)};
      });
  const std::size_t bad = found.first;
  if (bad == n)
    return std::sqrt(found.speed2);
  const Vec3& x = m_fluid.x[bad];
  const Vec3& v = m_fluid.v[bad];
  std::ostringstream s;
  s << "unstable at step " << m_stepCount << " (t = " << m_time << " s): particle " << m_fluid.id[bad] << " ";
  if (!x.allFinite() || !v.allFinite()) {
    s << "has a non-finite position or velocity";
  } else if (v.squaredNorm() > maxSpeed2) {
    s << "moves at " << v.norm() << " m/s, above max_speed " << m_params.maxSpeed << " m/s";
  } else {
    s << "left the domain at " << formatVec(x);
  }
  throw InstabilityError(s.str());
}

std::size_t Simulation::holdCoarse() {
  // A step between two synchronised ones: the particles on time level 1 take no part in the solves (their
  // neighbour lists are emptied, so each solver pass costs them nothing); they keep their density and warm
  // starts and drift with their velocity. Their neighbours still see them, as particles of known velocity
  // whose stiffness is zero, and push them with the reaction of their own pressure (reactOnHeld).
  using Range = tbb::blocked_range<std::size_t>;
  const std::size_t n = m_fluid.size();
  parallelSelect(n, 4096, m_held, [&](std::size_t i) { return (m_fluid.flags[i] & kFlagTimeLevel1) != 0; });
  if (m_held.empty())
    return 0;
  const std::size_t h = m_held.size();
  m_heldMask.assign(n, 0);
  parallelFor(Range(0, h, 4096), [&](const Range& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k)
      m_heldMask[m_held[k]] = 1;
  });
  const std::vector<std::uint8_t>& mark = m_heldMask;
  // the held particles' active fluid neighbours, for the reaction of their pressure
  filterRows(
      m_fluidNbrs, h, [&](std::size_t k) { return m_held[k]; }, [](std::size_t) { return true; },
      [&](std::uint32_t j) { return !mark[j]; }, m_heldNbrs);
  m_heldRho.resize(h);
  m_heldKappa.resize(h);
  m_heldKappaV.resize(h);
  parallelFor(Range(0, h, 1024), [&](const Range& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      const std::uint32_t i = m_held[k];
      m_heldRho[k] = m_fluid.rho[i];
      m_heldKappa[k] = m_fluid.kappa[i];
      m_heldKappaV[k] = m_fluid.kappaV[i];
      // no warm start: a held particle's stiffness stays zero in this step's solves
      m_fluid.kappa[i] = 0;
      m_fluid.kappaV[i] = 0;
    }
  });
  // (a scratch each: the two lists' sizes differ by an order of magnitude, and a shared one would hand each
  // list the other's arrays, reallocated at the next search)
  dropNeighbors(m_fluidNbrs, mark, m_dropScratchFluid);
  dropNeighbors(m_boundaryNbrs, mark, m_dropScratchBoundary);
  return h;
}

void Simulation::reactOnHeld(Real dt) {
  // The solves moved each active particle i by -V_j (dt kappa_i + kappaV_i) grad W_ij against a held
  // neighbour j whose stiffness was zero; j takes the opposite momentum, V_i (dt kappa_i + kappaV_i) grad
  // W_ij (m_i V_j = m_j V_i), so the interface conserves momentum like any pair of the solve. (kappa is the
  // stiffness the density solve applied in this step, kappaV the divergence solve's times its step.)
  const ParticleSet& p = m_fluid;
  const Real invRho0 = Real(1) / Real(m_params.restDensity);
  parallelFor(tbb::blocked_range<std::size_t>(0, m_held.size(), 256),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t k = r.begin(); k < r.end(); ++k) {
                  const std::uint32_t j = m_held[k];
                  Vec3 dv = Vec3::Zero();
                  for (std::uint32_t q = m_heldNbrs.offsets[k]; q < m_heldNbrs.offsets[k + 1]; ++q) {
                    const std::uint32_t i = m_heldNbrs.indices[q];
                    const Vec3 xij = p.x[i] - p.x[j];
                    const Real g = CubicSpline::gradFactor(xij.norm(), pairSupport(p.H[i], p.H[j]));
                    dv += (p.m[i] * invRho0 * (dt * p.kappa[i] + p.kappaV[i]) * g) * xij;
                  }
                  m_fluid.v[j] += dv;
                }
              });
}

void Simulation::restoreHeld(std::vector<Real>& field, const std::vector<Real>& saved) const {
  parallelFor(tbb::blocked_range<std::size_t>(0, m_held.size(), 4096),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t k = r.begin(); k < r.end(); ++k)
                  field[m_held[k]] = saved[k];
              });
}

std::size_t Simulation::assignTimeLevels(Real dt) {
  // After a synchronised step, on its neighbour lists. A candidate is a particle whose own CFL step,
  // cfl_factor (H_i / 2) / (|v_i| + dt |a_i|) with its whole acceleration of the step, is at least twice the
  // step, with no moving collider near (its own CFL counts for its neighbours) and not a split child that
  // still blends. Level 1 takes the candidates whose neighbours are all candidates: one layer of particles
  // that could hold but take part lies between the held ones and the particles that need the short step
  // (the buffer of regional time stepping, Goswami & Batty 2014).
  using Range = tbb::blocked_range<std::size_t>;
  const std::size_t n = m_fluid.size();
  const std::size_t nStatic = m_boundary.staticCount();
  const Real cfl = Real(m_params.cflFactor);
  // a held particle's two steps of drift and one of solve must stay a step the solver is trusted with
  const bool withinMax = 2.0 * double(dt) <= m_params.dtMax;
  m_timeLevelCandidate.resize(n);
  std::uint8_t* candidate = m_timeLevelCandidate.data();
  parallelFor(Range(0, n, 2048), [&](const Range& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      bool ok = withinMax && m_fluid.parentIdOf(i) == kNoParent;
      const Real speed = m_fluid.v[i].norm() + dt * m_fluid.a[i].norm();
      if (ok && speed > Real(0))
        ok = cfl * Real(0.5) * m_fluid.H[i] / speed >= Real(2) * dt;
      for (std::uint32_t k = m_boundaryNbrs.offsets[i]; ok && k < m_boundaryNbrs.offsets[i + 1]; ++k)
        ok = m_boundaryNbrs.indices[k] < nStatic;
      candidate[i] = ok ? 1 : 0;
    }
  });
  // (a count: exact in any order)
  return parallelReduce(
      Range(0, n, 2048), std::size_t(0),
      [&](const Range& r, std::size_t count) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          bool level1 = candidate[i] != 0;
          for (std::uint32_t k = m_fluidNbrs.offsets[i]; level1 && k < m_fluidNbrs.offsets[i + 1]; ++k)
            level1 = candidate[m_fluidNbrs.neighbor(i, k)] != 0;
          if (level1) {
            m_fluid.flags[i] |= kFlagTimeLevel1;
            ++count;
          } else {
            m_fluid.flags[i] &= ~kFlagTimeLevel1;
          }
        }
        return count;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
}

void Simulation::step() {
  StepStats st;
  auto t0 = Clock::now();
  updateColliders();
  auto t1 = Clock::now();
  st.times.boundaries = seconds(t0, t1);

  // the fluid's lists of the current positions when prepareNeighbors() built them since the last step (the
  // colliders just moved: the boundary's lists are built again)
  if (m_neighborsCurrent)
    searchBoundaryNeighbors();
  else
    searchNeighbors();
  m_neighborsCurrent = false;
  auto t2 = Clock::now();
  st.times.neighbors = seconds(t1, t2) + m_preparedSeconds;
  m_preparedSeconds = 0.0;
  const std::size_t n = m_fluid.size();
  if (n > 0) {
    st.fluidNeighbors = double(m_fluidNbrs.entries()) / double(n);
    st.boundaryNeighbors = double(m_boundaryNbrs.entries()) / double(n);
  }

  // time levels: every other step is a synchronised one, where every particle takes part
  const bool multiRate = m_params.timeLevels > 1;
  const bool syncStep = !multiRate || m_stepCount % 2 == 0;
  st.heldParticles = syncStep ? 0 : holdCoarse();
  if (syncStep && m_heldLastStep) {
    // the particles held in the last step drifted through it: they get its gravity impulse now, so every
    // particle receives gravity for every step (also when time_levels was set to 1 since: it is live)
    const Vec3 g(Real(m_params.gravity[0]), Real(m_params.gravity[1]), Real(m_params.gravity[2]));
    parallelFor(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        if (m_fluid.flags[i] & kFlagTimeLevel1)
          m_fluid.v[i] += m_dt * g;
      }
    });
  }
  m_heldLastStep = st.heldParticles > 0;

  SolverContext ctx{m_fluid, m_boundary, m_fluidNbrs, m_boundaryNbrs, m_params};
  if (!m_held.empty()) {
    ctx.held = m_heldMask.data();  // (holdCoarse)
    ctx.heldCount = m_held.size();
  }
  m_solver.resetBoundaryImpulse();
  double blendTime = 0.0;
  if (adaptive()) {
    // temporal blending after a split (docs/method.md, Adaptivity): velocities before the densities, whose
    // pass also gives the divergence solve its first density rates
    Adaptivity::blendSplitVelocities(m_fluid, m_params);
    const auto tb = Clock::now();
    blendTime += seconds(t2, tb);
    t2 = tb;
  }
  // (levels and adaptation need every particle's neighbours: only on synchronised steps)
  // (a step between two synchronised ones that holds no particle is a full step: where nothing can be held,
  // time_levels = 2 runs as one time step does)
  const bool adaptNow = adaptive() && (syncStep || st.heldParticles == 0) &&
                        m_stepCount % std::uint64_t(std::max(1, m_params.adaptationPeriod)) == 0;
  // the levels of every levels_period-th adaptation step; the optimal masses are kept in between. Their
  // neighbour sums come with the density pass.
  const bool levelsNow = adaptNow && m_stepCount % (std::uint64_t(std::max(1, m_params.adaptationPeriod)) *
                                                    std::uint64_t(std::max(1, m_params.levelsPeriod))) ==
                                         0;
  const bool levelSums =
      levelsNow && m_mode == AdaptivityMode::FluidPlaying;  // (vorticity, velocity difference)
  st.densityError = m_solver.computeDensityAndFactor(ctx, levelSums ? &m_levelSums : nullptr);
  if (!m_held.empty()) {
    // a held particle's density is not evaluated in this step (its list is empty; it counted as no error): it
    // counts with the density it was held with, so that the step's mean stays one over every particle
    const double invRho0 = 1.0 / m_params.restDensity;
    const double held = parallelDeterministicReduce(
        tbb::blocked_range<std::size_t>(0, m_held.size(), 4096), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double acc) {
          for (std::size_t k = r.begin(); k < r.end(); ++k)
            acc += std::max(0.0, double(m_heldRho[k]) * invRho0 - 1.0);
          return acc;
        },
        [](double a, double b) { return a + b; });
    st.densityError += held / double(n);
  }
  restoreHeld(m_fluid.rho, m_heldRho);
  auto t3 = Clock::now();
  st.times.density = seconds(t2, t3);
  if (adaptive()) {
    Adaptivity::blendSplitDensities(m_fluid,
                                    {m_grid, m_fluidCells, m_staticCells, m_kinematicCells, m_searchMaxH},
                                    m_boundary, m_params, m_latticeMass);
    const auto tb = Clock::now();
    blendTime += seconds(t3, tb);
    t3 = tb;
  }
  if (levelsNow) {
    computeLevels(true, &m_levelSums);  // (used when the density pass filled them)
    const auto tl = Clock::now();
    st.times.levels = seconds(t3, tl);
    t3 = tl;
  }

  if (m_params.divergenceSolve)
    st.divergenceIterations = m_solver.divergenceSolve(ctx, m_dt).iterations;
  restoreHeld(m_fluid.kappaV, m_heldKappaV);
  auto t4 = Clock::now();
  st.times.divergence = seconds(t3, t4);

  m_solver.nonPressureForces(ctx, m_dt);
  // a held particle drifts (its gravity comes with the next step)
  parallelFor(tbb::blocked_range<std::size_t>(0, m_held.size(), 4096),
              [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t k = r.begin(); k < r.end(); ++k)
                  m_fluid.a[m_held[k]].setZero();
              });
  auto t5 = Clock::now();
  st.times.viscosity = seconds(t4, t5);

  m_dt = m_solver.cflTimeStep(ctx, m_dt);
  const Real dt = m_dt;
  DfsphSolver::integrateVelocities(ctx, dt);
  auto t6 = Clock::now();

  const SolveResult density = m_solver.densitySolve(ctx, dt);
  st.densityIterations = density.iterations;
  st.solverDensityError = density.error;
  if (!m_held.empty())
    reactOnHeld(dt);
  restoreHeld(m_fluid.kappa, m_heldKappa);
  if (multiRate && syncStep)
    m_level1 = assignTimeLevels(dt);
  auto t7 = Clock::now();
  st.times.pressure = seconds(t6, t7);

  st.cagedParticles = m_solver.carryCaged(ctx);
  m_boundaryImpulse += m_solver.boundaryImpulse() + double(dt) * m_solver.boundaryForce();
  st.maxSpeed = double(integrateAndCheck(dt));
  m_time += double(dt);
  auto t8 = Clock::now();
  st.times.integrate = seconds(t5, t6) + seconds(t7, t8);
  if (adaptive()) {
    // this step's split children have blended once more; then new ones may be created (age 0)
    Adaptivity::ageSplitChildren(m_fluid, m_params);
    // the lists of this step's start still index the particles: nothing was reordered since
    double presortTime = 0.0;
    if (adaptNow) {
      const bool presort = presortSetting().load();
      st.adaptivity = adaptResolution(false, !presort);
      if (presort && st.adaptivity.splits + st.adaptivity.merges > 0) {
        // The removed particles are dropped by the sort by cell that the next step's search would make of
        // the compacted particles: made here on the kept ones, it gives the same order (a stable sort of the
        // same particles in the same relative order) without a separate pass that moves every field. Nothing
        // moves the fluid before that search, which then skips its sort; the time counts as the next step's
        // neighbour search, as prepareNeighbors() does.
        const auto ts = Clock::now();
        sortFluid(&m_adaptivity.kept());
        m_fluidPresorted = true;
        presortTime = seconds(ts, Clock::now());
        m_preparedSeconds += presortTime;
      }
    }
    if (st.adaptivity.splits + st.adaptivity.merges > 0) {
      // the particles were added and removed: the lists no longer index them (capacity is kept for the next
      // search)
      m_fluidNbrs.clear();
      m_boundaryNbrs.clear();
    }
    Adaptivity::blendSupports(m_fluid, m_params, m_latticeMass);
    st.times.adaptation = seconds(t8, Clock::now()) + blendTime - presortTime;
  }
  if (st.heldParticles > 0) {
    // the held particles' lists were emptied: the lists no longer hold all neighbours
    m_fluidNbrs.clear();
    m_boundaryNbrs.clear();
  }
  m_held.clear();
  ++m_stepCount;
  st.dt = dt;
  m_last = st;
  if (st.maxSpeed > m_run.maxSpeed)
    m_run.maxSpeedTime = m_time;
  m_run.add(st, n);
  if (multiRate)
    m_run.level1ParticleSteps += m_level1;
}

double Simulation::pressure(std::size_t i) const {
  // the divergence stiffness is stored multiplied by its step size (see DfsphSolver::divergenceSolve)
  const double k = double(m_fluid.kappa[i]) + (m_dt > 0 ? double(m_fluid.kappaV[i]) / double(m_dt) : 0.0);
  const double rho = m_fluid.rho[i];
  return k * rho * rho / m_params.restDensity;
}

std::size_t Simulation::memoryBytes() const {
  std::size_t bytes = 0;
  for (const MemoryItem& item : memoryBreakdown())
    bytes += item.bytes;
  return bytes;
}

std::vector<MemoryItem> Simulation::memoryBreakdown() const {
  std::vector<MemoryItem> out;
  m_fluid.memoryBreakdown(out);
  m_boundary.memoryBreakdown(out);
  auto lists = [&out](const char* name, const NeighborList& list) {
    MemoryItem item{name, 0, 0};
    countVector(item, list.offsets);
    countVector(item, list.indices);
    countVector(item, list.deltas);
    countVector(item, list.chunkCounts);
    out.push_back(item);
  };
  lists("neighbours: fluid lists", m_fluidNbrs);
  lists("neighbours: boundary lists", m_boundaryNbrs);
  MemoryItem held{"time levels: held particles, lists and fields", 0, 0};
  countVector(held, m_held);
  countVector(held, m_heldRho);
  countVector(held, m_heldKappa);
  countVector(held, m_heldKappaV);
  countVector(held, m_heldNbrs.offsets);
  countVector(held, m_heldNbrs.indices);
  countVector(held, m_heldNbrs.chunkCounts);
  countVector(held, m_heldMask);
  countVector(held, m_dropScratchFluid.offsets);
  countVector(held, m_dropScratchFluid.indices);
  countVector(held, m_dropScratchFluid.deltas);
  countVector(held, m_dropScratchBoundary.offsets);
  countVector(held, m_dropScratchBoundary.indices);
  countVector(held, m_timeLevelCandidate);
  out.push_back(held);
  MemoryItem cells{"grid: cell ranges (fluid, static, kinematic), sort order, walls' clearance", 0, 0};
  for (const auto* v : {&m_order, &m_fluidCells, &m_staticCells, &m_kinematicCells})
    countVector(cells, *v);
  cells.bytes += m_staticClearance.memoryBytes();
  cells.used += m_staticClearance.memoryBytes();
  out.push_back(cells);
  // the members of other classes report their capacity only: their spare part is not known here
  out.push_back({"grid: sort keys and row starts", m_grid.memoryBytes(), m_grid.memoryBytes()});
  out.push_back({"neighbour search scratch", m_search.memoryBytes(), m_search.memoryBytes()});
  out.push_back(
      {"solver: per-particle scratch and per-pair caches", m_solver.memoryBytes(), m_solver.memoryBytes()});
  const std::size_t levelBytes = m_levels.memoryBytes() + m_levelSums.memoryBytes();
  MemoryItem levels{"levels: scratch, the density pass's sums and target masses", levelBytes, levelBytes};
  countVector(levels, m_target);
  out.push_back(levels);
  out.push_back({"adaptivity scratch", m_adaptivity.memoryBytes(), m_adaptivity.memoryBytes()});
  return out;
}

}  // namespace fp::sim
