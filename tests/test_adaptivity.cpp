// The adaptivity's parts on hand-built cases: level mapping and optimal mass, split templates, and split,
// merge and share on random neighbourhoods (conservation, walls, orientation choice). Tests named *Small*
// also run under the sanitizers in CI.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>

#include "sim/adaptivity.h"
#include "sim/dfsph_solver.h"
#include "sim/kernels.h"
#include "sim/levels.h"
#include "sim/metrics.h"
#include "sim/parallel.h"
#include "sim/signed_distance.h"
#include "sim/simulation.h"
#include "sim/split_templates.h"
#include "tests/scene_fixtures.h"

using namespace fp::sim;

TEST(LevelsTest, RampAndLevelsAtTheIntervalEdgesSmall) {
  EXPECT_DOUBLE_EQ(levelRamp(1.0, 1.0, 3.0), 0.0);
  EXPECT_DOUBLE_EQ(levelRamp(0.0, 1.0, 3.0), 0.0);
  EXPECT_DOUBLE_EQ(levelRamp(2.0, 1.0, 3.0), 0.5);
  EXPECT_DOUBLE_EQ(levelRamp(3.0, 1.0, 3.0), 1.0);
  EXPECT_DOUBLE_EQ(levelRamp(9.0, 1.0, 3.0), 1.0);
  EXPECT_DOUBLE_EQ(visibleLevel(0.0, 0.04, 0.16), 0.0);
  EXPECT_DOUBLE_EQ(visibleLevel(0.10, 0.04, 0.16), 0.5);
  EXPECT_DOUBLE_EQ(refinementLevel(5.0, 12.0, 30.0, 8.0), 1.0);
  EXPECT_DOUBLE_EQ(refinementLevel(21.0, 12.0, 30.0, 8.0), 4.5);
  EXPECT_DOUBLE_EQ(refinementLevel(30.0, 12.0, 30.0, 8.0), 8.0);
}

TEST(LevelsTest, OptimalMassOnHandComputedCasesSmall) {
  const double mf = 2.0;
  const double mb = 54.0;  // ratio 27
  // surface: finest, whatever the other levels
  EXPECT_DOUBLE_EQ(optimalMass(0.0, 1.0, 1.0, mf, mb), 2.0);
  EXPECT_DOUBLE_EQ(optimalMass(0.0, 8.0, 8.0, mf, mb), 2.0);
  // deep and calm: coarsest
  EXPECT_DOUBLE_EQ(optimalMass(1.0, 1.0, 1.0, mf, mb), 54.0);
  // halfway down: 2 + 0.5 * 52
  EXPECT_DOUBLE_EQ(optimalMass(0.5, 1.0, 1.0, mf, mb), 28.0);
  // deep but vortical (R_omega = 4) and shearing (R_nu = 2): 2 + 52 / 8
  EXPECT_DOUBLE_EQ(optimalMass(1.0, 4.0, 2.0, mf, mb), 8.5);
  // support follows the mass: 27 times the mass, 3 times the support
  EXPECT_NEAR(supportForMass(Real(27), Real(1), Real(0.01)), 0.12, 1e-6);
}

TEST(SplitTemplatesTest, PatternsAreCentredAndShapedSmall) {
  const SplitTemplates& t = SplitTemplates::get();
  for (int n = SplitTemplates::kMinChildren; n <= SplitTemplates::kMaxChildren; ++n) {
    const auto& x = t.offsets(n);
    ASSERT_EQ(int(x.size()), n);
    Vec3d mean = Vec3d::Zero();
    double nearest = 1e9;
    for (std::size_t a = 0; a < x.size(); ++a) {
      mean += x[a] / double(n);
      EXPECT_LT(x[a].norm(), 2.0) << "n = " << n;  // inside the parent's spacing
      for (std::size_t b = a + 1; b < x.size(); ++b)
        nearest = std::min(nearest, (x[a] - x[b]).norm());
    }
    EXPECT_LT(mean.norm(), 1e-9) << "n = " << n;
    // no stacked children: at least half the children's own spacing 2 n^(-1/3) apart
    EXPECT_GT(nearest, 0.5 * 2.0 / std::cbrt(double(n))) << "n = " << n;
    EXPECT_LT(t.residual(n), 0.02) << "n = " << n;
  }
  // 1:2 is a segment through the parent, 1:3 the paper's equilateral triangle, 1:4 a regular tetrahedron
  const auto& two = t.offsets(2);
  EXPECT_NEAR((two[0] + two[1]).norm(), 0.0, 1e-9);
  const auto& three = t.offsets(3);
  const double a = (three[0] - three[1]).norm();
  EXPECT_NEAR((three[1] - three[2]).norm(), a, 1e-3 * a);
  EXPECT_NEAR((three[2] - three[0]).norm(), a, 1e-3 * a);
  const auto& four = t.offsets(4);
  const double e = (four[0] - four[1]).norm();
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      EXPECT_NEAR((four[std::size_t(i)] - four[std::size_t(j)]).norm(), e, 1e-2 * e);
}

namespace {

/// Every fluid pair within its pair support, both ways, and every boundary particle within the particle's
/// pair support with the boundary: the lists by brute force, for small hand-built scenes.
void bruteForceLists(const ParticleSet& p, const BoundarySet& boundary, NeighborList& fluidNbrs,
                     NeighborList& boundaryNbrs) {
  fluidNbrs.offsets.assign(1, 0);
  boundaryNbrs.offsets.assign(1, 0);
  fluidNbrs.indices.clear();
  boundaryNbrs.indices.clear();
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = 0; j < p.size(); ++j) {
      if (j != i && (p.x[i] - p.x[j]).norm() < pairSupport(p.H[i], p.H[j]))
        fluidNbrs.indices.push_back(std::uint32_t(j));
    }
    fluidNbrs.offsets.push_back(std::uint32_t(fluidNbrs.indices.size()));
    for (std::size_t b = 0; b < boundary.size(); ++b) {
      if ((p.x[i] - boundary.x[b]).norm() < pairSupport(p.H[i], boundary.support()))
        boundaryNbrs.indices.push_back(std::uint32_t(b));
    }
    boundaryNbrs.offsets.push_back(std::uint32_t(boundaryNbrs.indices.size()));
  }
}

/// The mass of a particle of radius r on the rest lattice (spacing 2 r) at the rest density of `params` [kg].
Real restLatticeMass(const SimParams& params, Real r) {
  return Real(params.restDensity * 8.0 * double(r) * r * r);
}

/// A 6 x 4 x 6 lattice block of spacing 2r at rest on a floor whose top is y = 0, x from 0.45 m, z from -0.05
/// m.
void addRestingBlock(ParticleSet& p, Real m, Real H, Real r, Real rho) {
  for (int ix = 0; ix < 6; ++ix)
    for (int iy = 0; iy < 4; ++iy)
      for (int iz = 0; iz < 6; ++iz)
        p.add(Vec3(Real(0.45) + Real(2 * ix) * r, Real(2 * iy + 1) * r, Real(-0.05) + Real(2 * iz) * r),
              Vec3::Zero(), m, H, rho);
}

/// A jittered cloud of particles of mixed masses inside a container, with neighbour lists, ready for one
/// adaptation step.
struct Neighbourhood {
  SimParams params;
  ParticleSet p;
  BoundarySet boundary;
  std::vector<ColliderState> colliders;
  UniformGrid grid;
  NeighborList fluidNbrs;
  NeighborList boundaryNbrs;
  Real mFine = 0;

  explicit Neighbourhood(unsigned seed) {
    const Real r = Real(0.01);
    params.particleRadius = r;
    params.transferRate = 0.25;
    mFine = restLatticeMass(params, r);
    ColliderState tank;
    tank.desc.shape = ShapeType::Box;
    tank.desc.container = true;
    tank.desc.halfExtents = Vec3d::Constant(0.1);
    colliders.push_back(tank);
    boundary.build(colliders, r);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> jitter(-0.3f * r, 0.3f * r);
    std::uniform_real_distribution<Real> massFactor(0.6f, 4.0f);
    std::uniform_real_distribution<Real> speed(-1.0f, 1.0f);
    const Real ratios[] = {0.3f, 0.7f, 1.0f, 1.5f, 3.0f, 9.0f};
    std::uniform_int_distribution<int> pick(0, 5);
    for (int z = -4; z <= 4; ++z)
      for (int y = -4; y <= 4; ++y)
        for (int x = -4; x <= 4; ++x) {
          const Vec3 pos =
              Real(2) * r * Vec3(Real(x), Real(y), Real(z)) + Vec3(jitter(rng), jitter(rng), jitter(rng));
          const Real m = massFactor(rng) * mFine;
          const std::size_t i =
              p.add(pos, Vec3(speed(rng), speed(rng), speed(rng)), m, supportForMass(m, mFine, r), 1000.0f);
          p.mOpt[i] = m / ratios[pick(rng)];
        }
    grid.setup(Aabb(Vec3d::Constant(-0.15), Vec3d::Constant(0.15)), Real(4) * r);
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> staticCells;
    std::vector<std::uint32_t> fluidCells;
    std::vector<std::uint32_t> noCells(grid.cellCount() + 1, 0);
    grid.sort(boundary.x.data(), boundary.staticCount(), order, staticCells);
    boundary.permute(0, order);
    grid.sort(p.x.data(), p.size(), order, fluidCells);
    p.permute(order);
    Real maxH = boundary.support();
    for (Real h : p.H)
      maxH = std::max(maxH, h);
    NeighborSearch search;
    search.build(grid, p.x, p.H, {GridPoints{p.x.data(), p.H.data(), 0, &fluidCells, 0}}, 0, maxH, fluidNbrs);
    search.build(grid, p.x, p.H,
                 {GridPoints{boundary.x.data(), nullptr, boundary.support(), &staticCells, 0},
                  GridPoints{boundary.x.data(), nullptr, boundary.support(), &noCells, 0}},
                 -1, maxH, boundaryNbrs);
  }

  AdaptContext context(double time) {
    return AdaptContext{p, fluidNbrs, boundaryNbrs, boundary, colliders, params, mFine, time, 7};
  }

  /// every particle five times its optimal mass: all split, many of them next to the container's walls
  void makeAllTooHeavy() {
    for (std::size_t i = 0; i < p.size(); ++i)
      p.mOpt[i] = p.m[i] / Real(5);
  }
};

}  // namespace

TEST(AdaptivityTest, SplitMergeShareConserveMassAndMomentumSmall) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    Neighbourhood nb(seed);
    const std::size_t before = nb.p.size();
    const double mass = nb.p.totalMass();
    const Vec3d momentum = nb.p.totalMomentum();
    Adaptivity adaptivity;
    const AdaptivityStats st = adaptivity.adapt(nb.context(0.5), true);
    EXPECT_GT(st.splits, 10u);
    EXPECT_GT(st.merges, 10u);
    EXPECT_GT(st.redistributions, 10u);
    EXPECT_EQ(nb.p.size(), before + st.children - st.splits - st.merges);
    // float masses: the sums agree to single-precision round-off
    EXPECT_NEAR(nb.p.totalMass(), mass, 1e-6 * mass);
    EXPECT_LT((nb.p.totalMomentum() - momentum).norm(), 1e-6 * mass);
    for (Real m : nb.p.m)
      EXPECT_GT(m, 0.0f);
  }
}

TEST(AdaptivityTest, SplitChildrenTakeTheirParentsCagedAndSurfaceBitsSmall) {
  // A parent that the boundary alone caged leaves its children counted as cage (kFlagCaged) until the next
  // density pass decides for each of them, and a surface parent's children are surface particles; neither bit
  // is given to the children of a parent without it.
  Neighbourhood nb(3);
  nb.makeAllTooHeavy();
  nb.params.splitBlendSteps = 5;  // (the children name their parent for the blending)
  std::vector<std::uint32_t> flagsById;
  for (std::size_t i = 0; i < nb.p.size(); ++i) {
    std::uint32_t& f = nb.p.flags[i];
    f &= ~std::uint32_t(kFlagCaged | kFlagSurface);
    if (nb.p.id[i] % 2 == 1)
      f |= kFlagCaged;
    if (nb.p.id[i] % 3 == 0)
      f |= kFlagSurface;
    if (nb.p.id[i] >= flagsById.size())
      flagsById.resize(nb.p.id[i] + 1, ~0u);
    flagsById[nb.p.id[i]] = f;
  }
  Adaptivity adaptivity;
  const AdaptivityStats st = adaptivity.adapt(nb.context(0.5), true);
  ASSERT_GT(st.splits, 50u);
  std::size_t children = 0, caged = 0, surface = 0;
  for (std::size_t i = 0; i < nb.p.size(); ++i) {
    if (nb.p.id[i] < flagsById.size() && flagsById[nb.p.id[i]] != ~0u)
      continue;  // not a child of this step
    ++children;
    const std::uint32_t parent = nb.p.parentIdOf(i);
    ASSERT_LT(parent, flagsById.size()) << "child " << i;
    const std::uint32_t f = nb.p.flags[i];
    EXPECT_NE(f & kFlagSplit, 0u) << "child " << i;
    EXPECT_EQ(f & kFlagCaged, flagsById[parent] & kFlagCaged) << "child " << i;
    EXPECT_EQ(f & kFlagSurface, flagsById[parent] & kFlagSurface) << "child " << i;
    caged += (f & kFlagCaged) != 0;
    surface += (f & kFlagSurface) != 0;
  }
  EXPECT_EQ(children, st.children);
  // both kinds of parent split
  EXPECT_GT(caged, 0u);
  EXPECT_LT(caged, children);
  EXPECT_GT(surface, 0u);
  EXPECT_LT(surface, children);
}

namespace {

/// Checks one adapt() call against its record (Adaptivity::lastOperations) and the particles before and
/// after: every particle takes part in one operation at most, a receiver never splits, a receiver ends at or
/// below its optimal mass, the removed ones (merged, split) are gone and the others kept their id. Returns
/// the number of receivers.
std::size_t checkOneOperationPerParticle(const ParticleSet& before, const ParticleSet& after,
                                         const Adaptivity& adaptivity, const AdaptivityStats& st) {
  const std::vector<ParticleOps>& ops = adaptivity.lastOperations();
  EXPECT_EQ(ops.size(), before.size());
  std::vector<std::int64_t> now;  // id -> index after the step, -1 when gone
  for (std::size_t i = 0; i < after.size(); ++i) {
    if (after.id[i] >= now.size())
      now.resize(after.id[i] + 1, -1);
    now[after.id[i]] = std::int64_t(i);
  }
  auto indexAfter = [&](std::uint32_t id) { return id < now.size() ? now[id] : std::int64_t(-1); };
  std::size_t merged = 0, split = 0, received = 0;
  for (std::size_t i = 0; i < ops.size() && i < before.size(); ++i) {
    const ParticleOps& o = ops[i];
    EXPECT_EQ(o.id, before.id[i]);
    EXPECT_LE(o.count, 1) << "particle " << o.id << " took part in " << int(o.count)
                          << " operations in one step (kinds " << int(o.kinds) << ")";
    EXPECT_FALSE((o.kinds & kOpReceived) && (o.kinds & kOpSplit)) << "receiver " << o.id << " split";
    const std::int64_t j = indexAfter(o.id);
    merged += (o.kinds & kOpMerged) != 0;
    split += (o.kinds & kOpSplit) != 0;
    if (o.kinds & (kOpMerged | kOpSplit)) {
      EXPECT_EQ(j, -1) << "removed particle " << o.id << " still there";
      continue;
    }
    EXPECT_GE(j, 0) << "particle " << o.id << " lost without an operation";
    if (j < 0)
      continue;
    const Real m = after.m[std::size_t(j)];
    if (o.kinds & kOpReceived) {
      ++received;
      EXPECT_GT(m, before.m[i]);
      // a receiver ends at or below its optimal mass (so it is no split candidate because of what it got)
      EXPECT_LE(double(m), double(after.mOpt[std::size_t(j)]) * (1 + 1e-5)) << "receiver " << o.id;
    } else if (o.kinds & kOpShared) {
      EXPECT_LT(m, before.m[i]);
    } else {
      EXPECT_EQ(m, before.m[i]) << "particle " << o.id << " changed mass without an operation";
    }
  }
  EXPECT_EQ(merged, st.merges);
  EXPECT_EQ(split, st.splits);
  return received;
}

/// Fills all-pairs fluid neighbour lists for n particles (every other particle is a neighbour) and empty
/// boundary lists: small hand-built scenes whose particles all lie within each other's support.
void allPairs(std::size_t n, NeighborList& fluidNbrs, NeighborList& boundaryNbrs) {
  for (std::size_t i = 0; i < n; ++i) {
    fluidNbrs.offsets.push_back(std::uint32_t(fluidNbrs.indices.size()));
    boundaryNbrs.offsets.push_back(0);
    for (std::size_t j = 0; j < n; ++j)
      if (j != i)
        fluidNbrs.indices.push_back(std::uint32_t(j));
  }
  fluidNbrs.offsets.push_back(std::uint32_t(fluidNbrs.indices.size()));
  boundaryNbrs.offsets.push_back(0);
}

}  // namespace

namespace {

/// whether two particle sets hold the same particles, bit for bit, in every field the solver and the
/// adaptivity read
bool sameParticles(const ParticleSet& a, const ParticleSet& b) {
  auto same = [&](const auto& u, const auto& v) {
    return u.size() == v.size() && std::memcmp(u.data(), v.data(), u.size() * sizeof(u[0])) == 0;
  };
  return a.size() == b.size() && same(a.x, b.x) && same(a.v, b.v) && same(a.m, b.m) && same(a.H, b.H) &&
         same(a.mOpt, b.mOpt) && a.id == b.id && a.flags == b.flags && a.heavySteps == b.heavySteps &&
         a.parentId == b.parentId;
}

}  // namespace

TEST(AdaptivityTest, ThePrefilterOfDonorsChangesNothingWhateverTheThreadsSmall) {
  // adapt() leaves out, in a parallel pass, the merge and share donors whose capacity is already too small
  // (setAdaptivityPrefilter). The same neighbourhoods adapted with and without it, at 1 and 2 threads, end
  // bit for bit the same. Variant 1 lets transfers fill only the lightest neighbours, a tenth as fast, so
  // that many too-light particles find no room: the case the prefilter is for.
  struct Restore {
    ~Restore() { setAdaptivityPrefilter(true); }
  } restore;
  for (int variant = 0; variant < 2; ++variant) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      std::vector<ParticleSet> results;
      std::vector<AdaptivityStats> stats;
      std::size_t leftOut = 0;
      for (const bool prefilter : {false, true}) {
        for (const int threads : {1, 2}) {
          const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
          setAdaptivityPrefilter(prefilter);
          Neighbourhood nb(seed);
          if (variant == 1) {
            nb.params.lightBelow = 0.55;
            nb.params.mergeReceiversBelow = 0.55;
            nb.params.transferRate = 0.025;
          }
          Adaptivity adaptivity;
          stats.push_back(adaptivity.adapt(nb.context(0.5), true));
          results.push_back(nb.p);
          if (prefilter)
            leftOut = adaptivity.lastDonorsLeftOut();
          else
            EXPECT_EQ(adaptivity.lastDonorsLeftOut(), 0u);
        }
      }
      EXPECT_GT(stats[0].redistributions, 10u);
      if (variant == 0) {
        EXPECT_GT(stats[0].merges, 10u) << "seed " << seed;
      } else {
        EXPECT_GT(leftOut, 20u) << "seed " << seed;
      }
      for (std::size_t k = 1; k < results.size(); ++k) {
        EXPECT_TRUE(sameParticles(results[0], results[k]))
            << "variant " << variant << " seed " << seed << " run " << k;
        EXPECT_EQ(stats[k].merges, stats[0].merges);
        EXPECT_EQ(stats[k].splits, stats[0].splits);
        EXPECT_EQ(stats[k].redistributions, stats[0].redistributions);
      }
    }
  }
}

TEST(ParallelTest, SelectGivesTheAscendingIndicesOfASerialFilterSmall) {
  // across block edges and for a single block, at 1 and 2 threads
  for (const std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(37), std::size_t(4096),
                              std::size_t(4097), std::size_t(20000)}) {
    auto keep = [](std::size_t i) { return (i * 2654435761u) % 7 < 3; };
    std::vector<std::uint32_t> expected;
    for (std::size_t i = 0; i < n; ++i) {
      if (keep(i))
        expected.push_back(std::uint32_t(i));
    }
    for (const int threads : {1, 2}) {
      const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      std::vector<std::uint32_t> got{99, 98};  // replaced, not appended to
      parallelSelect(n, 4096, got, keep);
      EXPECT_EQ(got, expected) << "n " << n << " threads " << threads;
    }
  }
}

TEST(AdaptivityTest, EachParticleTakesPartInOneOperationPerStepSmall) {
  // Random neighbourhoods of mixed masses: many merges, splits and shares in one step. Then the same with a
  // full transfer rate and split/share thresholds close to 1, where a receiver that kept receiving or was not
  // capped at its optimal mass would become a split candidate in the same step.
  for (int variant = 0; variant < 2; ++variant) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      Neighbourhood nb(seed);
      if (variant == 1) {
        nb.params.transferRate = 1.0;
        nb.params.shareAbove = 1.05;
        nb.params.splitAbove = 1.2;
      }
      const ParticleSet before = nb.p;
      Adaptivity adaptivity;
      const AdaptivityStats st = adaptivity.adapt(nb.context(0.5), true);
      EXPECT_GT(st.merges, 10u);
      EXPECT_GT(st.splits, 10u);
      EXPECT_GT(st.redistributions, 10u);
      const std::size_t received = checkOneOperationPerParticle(before, nb.p, adaptivity, st);
      EXPECT_GT(received, 50u) << "variant " << variant << " seed " << seed;
    }
  }
}

TEST(AdaptivityTest, ChildrenNeverLandInAWallSmall) {
  Neighbourhood nb(11);
  nb.makeAllTooHeavy();
  Adaptivity adaptivity;
  const AdaptivityStats st = adaptivity.adapt(nb.context(1.0), true);
  EXPECT_GT(st.splits, 200u);
  std::size_t children = 0;
  for (std::size_t i = 0; i < nb.p.size(); ++i) {
    if (!(nb.p.flags[i] & kFlagSplit))
      continue;
    ++children;
    const double rChild = nb.params.particleRadius * std::cbrt(double(nb.p.m[i]) / double(nb.mFine));
    EXPECT_GE(signedDistance(nb.colliders[0].desc, nb.p.x[i].cast<double>()), 2.0 * rChild * (1 - 1e-4));
    EXPECT_EQ(nb.p.splitTime[i], Real(1.0));
  }
  EXPECT_EQ(children, st.children);
}

TEST(AdaptivityTest, ABlockedSplitIsPlannedAgainOnlyAfterFourStepsSmall) {
  // Every particle far too heavy: the ones next to the walls whose every orientation puts a child in a wall
  // are blocked. The same neighbourhood again with only those heavy (nothing else to do, so the lists stay
  // valid from step to step): they are planned in the first step, left alone for three, planned again in the
  // fifth (before, a blocked split was planned in every step).
  std::vector<std::uint32_t> blockedIds;
  {
    Neighbourhood nb(11);
    nb.makeAllTooHeavy();
    Adaptivity adaptivity;
    const AdaptivityStats st = adaptivity.adapt(nb.context(1.0), true);
    ASSERT_GT(st.splitsBlocked, 0u);
    for (std::size_t i = 0; i < nb.p.size(); ++i) {
      if (!(nb.p.flags[i] & kFlagSplit) && nb.p.m[i] >= Real(nb.params.splitAbove) * nb.p.mOpt[i]) {
        blockedIds.push_back(nb.p.id[i]);
        // the split delay restarts four steps short of its end
        EXPECT_EQ(nb.p.heavySteps[i], std::uint32_t(nb.params.splitDelay - 4));
      }
    }
    EXPECT_EQ(blockedIds.size(), st.splitsBlocked);
  }
  Neighbourhood nb(11);
  for (std::size_t i = 0; i < nb.p.size(); ++i) {
    const bool blocked = std::find(blockedIds.begin(), blockedIds.end(), nb.p.id[i]) != blockedIds.end();
    nb.p.mOpt[i] = blocked ? nb.p.m[i] / Real(5) : nb.p.m[i];
  }
  Adaptivity adaptivity;
  std::vector<std::uint64_t> blockedPerStep;
  for (int step = 0; step < 9; ++step) {
    const AdaptivityStats st = adaptivity.adapt(nb.context(1.0), step == 0);
    EXPECT_EQ(st.splits + st.merges + st.redistributions, 0u) << "step " << step;
    blockedPerStep.push_back(st.splitsBlocked);
  }
  const std::uint64_t k = blockedIds.size();
  EXPECT_EQ(blockedPerStep, (std::vector<std::uint64_t>{k, 0, 0, 0, k, 0, 0, 0, k}));
}

TEST(AdaptivityTest, SettledSupportsFollowEveryMassChangeSmall) {
  // blendSupports skips the particles whose support is already their mass's own (kFlagSupportSettled); every
  // mass change must clear the flag. After merges, splits and shares, the supports blended with the skip
  // equal, bit for bit, those blended with every flag cleared, and end at their masses' own supports.
  for (unsigned seed = 1; seed <= 3; ++seed) {
    Neighbourhood nb(seed);
    nb.params.supportBlendSteps = 10;
    for (int k = 0; k < 3; ++k)
      Adaptivity::blendSupports(nb.p, nb.params, nb.mFine);
    for (std::size_t i = 0; i < nb.p.size(); ++i)
      ASSERT_TRUE(nb.p.flags[i] & kFlagSupportSettled) << "particle " << i << " not settled at the start";
    Adaptivity adaptivity;
    const AdaptivityStats st = adaptivity.adapt(nb.context(0.5), true);
    ASSERT_GT(st.merges + st.redistributions, 10u);
    ParticleSet all = nb.p;
    std::size_t differed = 0;
    for (int k = 0; k < 60; ++k) {
      for (std::uint32_t& f : all.flags)
        f &= ~std::uint32_t(kFlagSupportSettled);
      Adaptivity::blendSupports(all, nb.params, nb.mFine);
      Adaptivity::blendSupports(nb.p, nb.params, nb.mFine);
      ASSERT_EQ(std::memcmp(all.H.data(), nb.p.H.data(), all.H.size() * sizeof(Real)), 0) << "call " << k;
    }
    for (std::size_t i = 0; i < nb.p.size(); ++i) {
      const Real target = supportForMass(nb.p.m[i], nb.mFine, Real(nb.params.particleRadius));
      EXPECT_EQ(nb.p.H[i], target) << "particle " << i;
      differed += nb.p.flags[i] & kFlagSupportSettled ? 0 : 1;
    }
    EXPECT_EQ(differed, 0u);
  }
}

TEST(AdaptivityTest, ABoundedSplitErrorStopsAtItsBoundAndIsExactBelowItSmall) {
  // planSplit passes the best error so far as a bound: a candidate whose partial sum exceeds it is rejected
  // unfinished. Below the bound the error must be the whole one, bit for bit; at or above it, a partial sum
  // between the bound and the whole error (so `e < best` decides as the whole error would).
  Neighbourhood nb(5);
  const AdaptContext ctx = nb.context(0.0);
  const double r = nb.params.particleRadius;
  std::size_t stopped = 0;
  for (std::size_t o = 0; o < nb.p.size(); o += 7) {
    for (int n = 2; n <= 4; ++n) {
      const double radius = r * std::cbrt(double(nb.p.m[o]) / double(nb.mFine));
      for (int k = 0; k < 3; ++k) {
        const Quatd rot(Eigen::AngleAxisd(0.7 * k + 0.1 * n, Vec3d(1, 2, 3).normalized()));
        std::vector<Vec3> children;
        for (const Vec3d& offset : SplitTemplates::get().offsets(n))
          children.push_back((nb.p.x[o].cast<double>() + radius * (rot * offset)).cast<Real>());
        const double whole = Adaptivity::splitError(ctx, o, children);
        ASSERT_GT(whole, 0.0);
        EXPECT_EQ(Adaptivity::splitError(ctx, o, children, whole * 1.5), whole);
        EXPECT_EQ(Adaptivity::splitError(ctx, o, children, std::nextafter(whole, 2 * whole)), whole);
        for (double f : {0.01, 0.3, 0.9, 1.0}) {
          const double bound = whole * f;
          const double e = Adaptivity::splitError(ctx, o, children, bound);
          EXPECT_GE(e, bound);
          EXPECT_LE(e, whole);
          stopped += e < whole;
        }
      }
    }
  }
  // the bound does stop evaluations early
  EXPECT_GT(stopped, 100u);
}

/// E of a split written out as docs/method.md states it, kernel by kernel (the children with the parent's
/// support, their density error weighted by 1 - the blend weight at the split), the reference for the split
/// error's precomputed terms
double directSplitError(const AdaptContext& ctx, std::size_t o, const std::vector<Vec3>& children) {
  const ParticleSet& p = ctx.fluid;
  const Real rho0 = Real(ctx.params.restDensity);
  const Real Vo = p.m[o] / rho0;
  const Real Vs = Vo / Real(children.size());
  const Real Hs = p.H[o];
  double e = 0.0;
  for (std::uint32_t k = ctx.fluidNbrs.offsets[o]; k < ctx.fluidNbrs.offsets[o + 1]; ++k) {
    const std::uint32_t j = ctx.fluidNbrs.neighbor(o, k);
    double tau = -double(Vo) * CubicSpline::w((p.x[j] - p.x[o]).norm(), pairSupport(p.H[j], p.H[o]));
    for (const Vec3& xs : children)
      tau += double(Vs) * CubicSpline::w((p.x[j] - xs).norm(), pairSupport(p.H[j], Hs));
    e += tau * tau;
  }
  const double keep = 1.0 - double(Adaptivity::splitBlendWeight(0, ctx.params.splitBlendSteps));
  for (const Vec3& xs : children) {
    double rho = 0.0;
    for (const Vec3& xt : children)
      rho += double(Vs) * CubicSpline::w((xs - xt).norm(), Hs);
    for (std::uint32_t k = ctx.fluidNbrs.offsets[o]; k < ctx.fluidNbrs.offsets[o + 1]; ++k) {
      const std::uint32_t j = ctx.fluidNbrs.neighbor(o, k);
      rho += double(p.m[j] / rho0) * CubicSpline::w((xs - p.x[j]).norm(), pairSupport(Hs, p.H[j]));
    }
    const double sb = double(ctx.boundary.volumeScale(Hs));
    for (std::uint32_t k = ctx.boundaryNbrs.offsets[o]; k < ctx.boundaryNbrs.offsets[o + 1]; ++k) {
      const std::uint32_t b = ctx.boundaryNbrs.indices[k];
      rho += sb * double(ctx.boundary.psi[b]) *
             CubicSpline::w((xs - ctx.boundary.x[b]).norm(), pairSupport(Hs, ctx.boundary.support()));
    }
    const double tau = keep * (rho - double(p.rho[o]) / double(rho0));
    e += tau * tau;
  }
  return e;
}

TEST(AdaptivityTest, TheSplitErrorIsItsDirectSumBitForBitSmall) {
  // splitError gathers each parent's terms once for all its candidates, evaluates each neighbour-child kernel
  // once for both sums and each pair of children once, and skips the kernels beyond the support: the same
  // number, bit for bit, as the sum written out, for parents with and without wall neighbours; without
  // temporal blending and with it (the children's errors at half weight)
  for (int blend : {0, 10}) {
    Neighbourhood nb(11);
    nb.params.splitBlendSteps = blend;
    const AdaptContext ctx = nb.context(0.0);
    const double r = nb.params.particleRadius;
    std::size_t withWalls = 0, compared = 0;
    for (std::size_t o = 0; o < nb.p.size(); o += 5) {
      withWalls += nb.boundaryNbrs.count(o) > 0 ? 1 : 0;
      for (int n : {2, 3, 5, 8, 27}) {
        const double radius = r * std::cbrt(double(nb.p.m[o]) / double(nb.mFine));
        const Quatd rot(Eigen::AngleAxisd(0.3 + 0.2 * n, Vec3d(3, -1, 2).normalized()));
        std::vector<Vec3> children;
        for (const Vec3d& offset : SplitTemplates::get().offsets(n))
          children.push_back((nb.p.x[o].cast<double>() + radius * (rot * offset)).cast<Real>());
        const double direct = directSplitError(ctx, o, children);
        ASSERT_GT(direct, 0.0);
        EXPECT_EQ(Adaptivity::splitError(ctx, o, children), direct)
            << "parent " << o << ", " << n << " children, split_blend_steps " << blend;
        ++compared;
      }
    }
    EXPECT_GT(compared, 500u);
    EXPECT_GT(withWalls, 20u);
  }
}

TEST(AdaptivityTest, OrientationChoiceLowersTheSplitDensityErrorSmall) {
  // The reported errors (the plans') and the children really placed: each split's children, at the tail of
  // the set in plan order, are scored again with the public split error on an untouched copy of the
  // neighbourhood and compared with the unrotated template, which is always a candidate. Placing children in
  // an orientation other than the chosen one (or choosing badly) makes a placed split worse than the
  // unrotated one. (The old check, a reduction in [0, 1), held by construction.)
  double chosen = 0.0;
  double unrotated = 0.0;
  std::uint64_t compared = 0;
  double placedSum = 0.0;
  double unrotatedSum = 0.0;
  int interior = 0;
  int worse = 0;
  for (unsigned seed = 20; seed < 24; ++seed) {
    Neighbourhood nb(seed);
    Neighbourhood ref(seed);
    // the children's own densities (without the temporal blending's half), on the chosen orientation's
    // template (MovingTheChildrenLowersTheSplitErrorFromTheChosenRotationSmall moves them)
    nb.params.splitBlendSteps = 0;
    ref.params.splitBlendSteps = 0;
    nb.params.splitPositionSteps = 0;
    // the parents' densities as the solver sees them: the children are to reproduce them
    DfsphSolver solver;
    for (Neighbourhood* h : {&nb, &ref}) {
      SolverContext ctx{h->p, h->boundary, h->fluidNbrs, h->boundaryNbrs, h->params};
      solver.computeDensityAndFactor(ctx);
      for (std::size_t i = 0; i < h->p.size(); ++i)
        h->p.mOpt[i] = h->p.m[i] / Real(3);
    }
    Adaptivity adaptivity;
    const AdaptivityStats st = adaptivity.adapt(nb.context(0.0), true);
    chosen += st.splitErrorChosen;
    unrotated += st.splitErrorUnrotated;
    compared += st.splitsCompared;
    ASSERT_EQ(st.merges, 0u);
    ASSERT_EQ(st.children, 3 * st.splits);  // m / m_opt = 3: three children each
    const std::size_t first = nb.p.size() - st.children;
    const AdaptContext refCtx = ref.context(0.0);
    const double r = ref.params.particleRadius;
    for (std::size_t c = first; c < nb.p.size(); c += 3) {
      const std::vector<Vec3> placed(nb.p.x.begin() + std::ptrdiff_t(c),
                                     nb.p.x.begin() + std::ptrdiff_t(c + 3));
      const Vec3 centre = (placed[0] + placed[1] + placed[2]) / Real(3);
      std::size_t parent = 0;
      for (std::size_t i = 1; i < ref.p.size(); ++i)
        if ((ref.p.x[i] - centre).squaredNorm() < (ref.p.x[parent] - centre).squaredNorm())
          parent = i;
      ASSERT_LT((ref.p.x[parent] - centre).norm(), 1e-5f) << "children not centred on a parent";
      // away from the walls every orientation is valid, the unrotated one included
      if (ref.p.x[parent].cwiseAbs().maxCoeff() > 0.045f)
        continue;
      const double radius = r * std::cbrt(double(ref.p.m[parent]) / double(ref.mFine));
      std::vector<Vec3> straight;
      for (const Vec3d& offset : SplitTemplates::get().offsets(3))
        straight.push_back((ref.p.x[parent].cast<double>() + radius * offset).cast<Real>());
      const double ePlaced = Adaptivity::splitError(refCtx, parent, placed);
      const double eStraight = Adaptivity::splitError(refCtx, parent, straight);
      placedSum += ePlaced;
      unrotatedSum += eStraight;
      worse += ePlaced > eStraight * (1 + 1e-6) + 1e-12;
      ++interior;
    }
  }
  ASSERT_GT(compared, 500u);
  const double reduction = 1.0 - chosen / unrotated;
  // the paper reports 15.5 %; with 8 candidates we measure about 40 % on these neighbourhoods, 53 % with the
  // default 8 refining tries after them
  EXPECT_GT(reduction, 0.3) << "mean split error reduction " << reduction;
  std::printf("split error reduction by orientation: %.1f %% over %llu splits\n", 100.0 * reduction,
              (unsigned long long)compared);
  ASSERT_GT(interior, 300);
  EXPECT_EQ(worse, 0) << "placed splits worse than the unrotated template, of " << interior;
  const double placedReduction = 1.0 - placedSum / unrotatedSum;
  std::printf("placed children, %d interior splits: error reduction %.1f %%\n", interior,
              100.0 * placedReduction);
  EXPECT_NEAR(placedReduction, reduction, 0.1);
}

TEST(AdaptivityTest, OrientationRefinementLowersTheChosenSplitErrorSmall) {
  // The same neighbourhoods split with the best of 8 candidates, and with 8 refining tries after them: the
  // same parents split (the plans are made on the same state), every try is kept only when it lowers the
  // error, so the refined sum is at most the candidates' and, on a few hundred splits, clearly lower.
  double candidatesOnly = 0.0;
  double refined = 0.0;
  double unrotated[2] = {0.0, 0.0};
  std::uint64_t splits[2] = {0, 0};
  for (unsigned seed = 20; seed < 24; ++seed) {
    for (int refine : {0, 8}) {
      Neighbourhood nb(seed);
      nb.params.orientationRefinement = refine;
      nb.params.splitPositionSteps = 0;
      DfsphSolver solver;
      SolverContext ctx{nb.p, nb.boundary, nb.fluidNbrs, nb.boundaryNbrs, nb.params};
      solver.computeDensityAndFactor(ctx);
      for (std::size_t i = 0; i < nb.p.size(); ++i)
        nb.p.mOpt[i] = nb.p.m[i] / Real(3);
      Adaptivity adaptivity;
      const AdaptivityStats st = adaptivity.adapt(nb.context(0.0), true);
      (refine == 0 ? candidatesOnly : refined) += st.splitErrorChosen;
      unrotated[refine == 0 ? 0 : 1] += st.splitErrorUnrotated;
      splits[refine == 0 ? 0 : 1] += st.splitsCompared;
    }
  }
  ASSERT_GT(splits[0], 500u);
  EXPECT_EQ(splits[0], splits[1]);
  EXPECT_DOUBLE_EQ(unrotated[0], unrotated[1]);
  const double gain = 1.0 - candidatesOnly / unrotated[0];
  const double gainRefined = 1.0 - refined / unrotated[1];
  std::printf("split error reduction: %.1f %% with 8 candidates, %.1f %% with 8 refining tries\n", 100 * gain,
              100 * gainRefined);
  EXPECT_LE(refined, candidatesOnly);
  EXPECT_GT(gainRefined, gain + 0.02);
}

TEST(AdaptivityTest, TheSplitErrorGradientIsItsDerivativeSmall) {
  // the gradient the position refinement descends, against central differences of its own E (double
  // precision kernels), and that E against splitError's (single precision kernels); without temporal
  // blending and with it (the children's errors at half weight)
  for (int blend : {0, 10}) {
    Neighbourhood nb(11);
    nb.params.splitBlendSteps = blend;
    const AdaptContext ctx = nb.context(0.0);
    const double r = nb.params.particleRadius;
    std::size_t checked = 0;
    for (std::size_t o = 0; o < nb.p.size(); o += 7) {
      for (int n : {2, 3, 5, 8}) {
        const double radius = r * std::cbrt(double(nb.p.m[o]) / double(nb.mFine));
        const Quatd rot(Eigen::AngleAxisd(0.7 + 0.1 * n, Vec3d(1, 2, -2).normalized()));
        std::vector<Vec3d> children;
        std::vector<Vec3> childrenReal;
        for (const Vec3d& offset : SplitTemplates::get().offsets(n)) {
          childrenReal.push_back((nb.p.x[o].cast<double>() + radius * (rot * offset)).cast<Real>());
          children.push_back(childrenReal.back().cast<double>());
        }
        std::vector<Vec3d> gradient;
        const double e = Adaptivity::splitErrorGradient(ctx, o, children, gradient);
        ASSERT_EQ(gradient.size(), children.size());
        EXPECT_NEAR(e, Adaptivity::splitError(ctx, o, childrenReal), 1e-4 * e + 1e-12);
        double largest = 0.0;
        for (const Vec3d& g : gradient)
          largest = std::max(largest, g.norm());
        ASSERT_GT(largest, 0.0);
        const double h = 1e-7;  // [m]: children sit 5-40 mm apart
        std::vector<Vec3d> unused;
        for (std::size_t s = 0; s < children.size(); ++s) {
          for (int d = 0; d < 3; ++d) {
            std::vector<Vec3d> plus = children, minus = children;
            plus[s][d] += h;
            minus[s][d] -= h;
            const double fd = (Adaptivity::splitErrorGradient(ctx, o, plus, unused) -
                               Adaptivity::splitErrorGradient(ctx, o, minus, unused)) /
                              (2.0 * h);
            EXPECT_NEAR(gradient[s][d], fd, 1e-5 * largest)
                << "parent " << o << ", child " << s << " of " << n << ", split_blend_steps " << blend;
          }
        }
        ++checked;
      }
    }
    EXPECT_GT(checked, 400u);
  }
}

TEST(AdaptivityTest, MovingTheChildrenLowersTheSplitErrorFromTheChosenRotationSmall) {
  // The same neighbourhoods split without and with split_position_steps = 3: the same plans up to the
  // rotation (the rotated errors of the moved run are the other run's chosen ones, bit for bit), then the
  // moves lower E by a quarter or more; each split's children keep the parent's centre, stay within the
  // template's reach of it and keep 0.85 of a child's diameter apart.
  double rotatedOnly = 0.0, rotatedBeforeMoves = 0.0, moved = 0.0, unrotated[2] = {0.0, 0.0};
  std::uint64_t compared[2] = {0, 0};
  std::size_t groups = 0;
  double largestOffset = 0.0;
  for (unsigned seed = 20; seed < 24; ++seed) {
    for (int moves : {0, 3}) {
      Neighbourhood nb(seed);
      nb.params.splitPositionSteps = moves;
      DfsphSolver solver;
      SolverContext sctx{nb.p, nb.boundary, nb.fluidNbrs, nb.boundaryNbrs, nb.params};
      solver.computeDensityAndFactor(sctx);
      for (std::size_t i = 0; i < nb.p.size(); ++i)
        nb.p.mOpt[i] = nb.p.m[i] / Real(3);
      const ParticleSet before = nb.p;
      Adaptivity adaptivity;
      const AdaptivityStats st = adaptivity.adapt(nb.context(0.0), true);
      ASSERT_EQ(st.children, 3 * st.splits);
      unrotated[moves == 0 ? 0 : 1] += st.splitErrorUnrotated;
      compared[moves == 0 ? 0 : 1] += st.splitsCompared;
      if (moves == 0) {
        rotatedOnly += st.splitErrorChosen;
        EXPECT_EQ(st.splitErrorRotated, st.splitErrorChosen);
        continue;
      }
      rotatedBeforeMoves += st.splitErrorRotated;
      moved += st.splitErrorChosen;
      EXPECT_LE(st.splitErrorChosen, st.splitErrorRotated);
      const double reach = [] {
        double d = 0.0;
        for (const Vec3d& offset : SplitTemplates::get().offsets(3))
          d = std::max(d, offset.norm());
        return d;
      }();
      for (std::size_t c = nb.p.size() - st.children; c < nb.p.size(); c += 3) {
        const Vec3d centre =
            (nb.p.x[c].cast<double>() + nb.p.x[c + 1].cast<double>() + nb.p.x[c + 2].cast<double>()) / 3.0;
        std::size_t parent = 0;
        for (std::size_t i = 1; i < before.size(); ++i)
          if ((before.x[i].cast<double>() - centre).squaredNorm() <
              (before.x[parent].cast<double>() - centre).squaredNorm())
            parent = i;
        const Vec3d xo = before.x[parent].cast<double>();
        ASSERT_LT((xo - centre).norm(), 1e-6) << "children not centred on their parent";
        const double parentRadius =
            nb.params.particleRadius * std::cbrt(double(before.m[parent]) / double(nb.mFine));
        const double childDiameter = 2.0 * parentRadius / std::cbrt(3.0);
        for (int a = 0; a < 3; ++a) {
          const double offset = (nb.p.x[c + a].cast<double>() - xo).norm();
          EXPECT_LE(offset, reach * parentRadius * (1 + 1e-5));
          largestOffset = std::max(largestOffset, offset / (reach * parentRadius));
          for (int b = a + 1; b < 3; ++b)
            EXPECT_GE((nb.p.x[c + a] - nb.p.x[c + b]).norm(), 0.85 * childDiameter * (1 - 1e-5));
        }
        ++groups;
      }
    }
  }
  ASSERT_GT(compared[0], 500u);
  EXPECT_EQ(compared[0], compared[1]);
  EXPECT_EQ(unrotated[0], unrotated[1]);
  EXPECT_EQ(rotatedBeforeMoves, rotatedOnly);
  std::printf("split error reduction: %.1f %% by the orientation, %.1f %% with 3 moves (%zu splits)\n",
              100 * (1 - rotatedOnly / unrotated[0]), 100 * (1 - moved / unrotated[1]), groups);
  EXPECT_LT(moved, 0.75 * rotatedOnly);
  EXPECT_GT(groups, 500u);
}

TEST(AdaptivityTest, SupportsBlendTowardsTheirMassSmall) {
  SimParams params;
  params.particleRadius = 0.01;
  params.supportBlendSteps = 10;
  ParticleSet p;
  const Real mf = 1.0f;
  p.add(Vec3::Zero(), Vec3::Zero(), 1.0f, 0.12f, 1000.0f);  // a fresh child with its parent's support
  const Real target = supportForMass(1.0f, mf, 0.01f);
  Real previous = p.H[0];
  for (int k = 0; k < 10; ++k) {
    Adaptivity::blendSupports(p, params, mf);
    EXPECT_LT(p.H[0], previous);
    EXPECT_GE(p.H[0], target);
    previous = p.H[0];
  }
  // after the blend period about 5 % of the difference is left, then it snaps
  EXPECT_LT(p.H[0] - target, 0.08f * (0.12f - target));
  for (int k = 0; k < 40; ++k)
    Adaptivity::blendSupports(p, params, mf);
  EXPECT_EQ(p.H[0], target);
}

namespace {

/// A block of water at rest in a closed tank (r = 0.1 / 10.4 puts the lattice 2.4 r from the walls, where
/// they hold it)
SceneDesc restingBlockScene() {
  SceneDesc scene;
  scene.params.particleRadius = 0.1 / 10.4;
  ColliderDesc tank;
  tank.shape = ShapeType::Box;
  tank.container = true;
  tank.halfExtents = Vec3d(0.1, 0.15, 0.1);
  tank.position = Vec3d(0, 0.15, 0);
  scene.colliders.push_back(tank);
  scene.fluid.push_back(FluidBlock{Aabb(Vec3d(-0.1, 0, -0.1), Vec3d(0.1, 0.24, 0.1)), Vec3d::Zero()});
  scene.domain = Aabb(Vec3d(-0.15, -0.05, -0.15), Vec3d(0.15, 0.35, 0.15));
  return scene;
}

/// The block simulated one step at uniform resolution (the lists of the step still index its particles), and
/// a copy of its particles with the level estimator's fields at their defaults (a uniform run holds none)
struct RestingBlock {
  explicit RestingBlock(const SceneDesc& s) : scene(s), sim(s) {
    sim.step();
    p = sim.particles();
    p.setAdaptivityFields(true);
    for (const Vec3& x : p.x)
      top = std::max(top, x.y());
  }
  SceneDesc scene;
  Simulation sim;
  ParticleSet p;
  Real top = 0;  // the highest particle's height [m]
};

}  // namespace

TEST(LevelsTest, SurfaceOfARestingBlockIsItsTopFaceAndPhiGrowsWithDepthSmall) {
  // a block of water at rest in a closed tank: its free surface is the top face only (walls are not a
  // surface)
  RestingBlock block(restingBlockScene());
  const SceneDesc& scene = block.scene;
  const Simulation& sim = block.sim;
  ASSERT_TRUE(sim.neighborsValid());
  ParticleSet& p = block.p;
  const Real r = Real(scene.params.particleRadius);
  const Real top = block.top;
  SimParams params = scene.params;
  std::vector<Real> target;
  LevelEstimator levels;
  levels.compute(p, sim.fluidNeighbors(), sim.boundaryNeighbors(), sim.boundary(), params,
                 AdaptivityMode::FluidPlaying, sim.latticeMass(), target);
  int topLayer = 0, topFlagged = 0, interior = 0, interiorFlagged = 0;
  // mean phi per lattice layer below the top, in spacings
  std::vector<double> phiSum(8, 0.0);
  std::vector<int> phiCount(8, 0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const bool surface = p.flags[i] & kFlagSurface;
    const Real depth = top - p.x[i].y();
    if (depth < r) {
      ++topLayer;
      topFlagged += surface;
    } else if (depth > Real(3) * r) {
      // deeper than the top layer, walls and floor included
      ++interior;
      interiorFlagged += surface;
    }
    const int layer = int(std::lround(depth / (2 * r)));
    if (layer < 8 && std::abs(p.x[i].x()) < 0.05f && std::abs(p.x[i].z()) < 0.05f) {
      phiSum[std::size_t(layer)] += p.phi[i];
      ++phiCount[std::size_t(layer)];
    }
  }
  ASSERT_GT(topLayer, 40);
  ASSERT_GT(interior, 300);
  EXPECT_GT(topFlagged, 0.95 * topLayer) << topFlagged << " of " << topLayer;
  EXPECT_LT(interiorFlagged, 0.01 * interior) << interiorFlagged << " of " << interior;
  // phi: zero on top, one spacing more per layer, capped at surface_distance_hi
  EXPECT_NEAR(phiSum[0] / phiCount[0], 0.0, 0.1 * r);
  const double cap = params.surfaceDistanceHi * r;
  for (int layer = 1; layer < 8; ++layer) {
    ASSERT_GT(phiCount[std::size_t(layer)], 0);
    const double mean = phiSum[std::size_t(layer)] / phiCount[std::size_t(layer)];
    EXPECT_NEAR(mean, std::min(cap, 2.0 * r * layer), 0.2 * r) << "layer " << layer;
  }
  // R_phi and the optimal mass follow: finest on top, coarsest below the cap
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.phi[i] >= Real(cap) * Real(0.999)) {
      EXPECT_NEAR(p.levelPhi[i], 1.0f, 2e-3f);
      EXPECT_NEAR(target[i], sim.latticeMass() * Real(params.massRatio), 2e-3f * target[i]);
    }
    if (p.flags[i] & kFlagSurface) {
      EXPECT_EQ(target[i], sim.latticeMass());
    }
  }
}

TEST(LevelsTest, RefinementForDynamicsKeepsAMarginOnTheSurfacesTimeStepSmall) {
  // cfl_limited_refinement: the resting block sheared (v_x = U + S (top - y), vorticity S, slowest at the
  // surface).
  // Deep particles are refined for their vorticity, but a particle moving at v keeps the mass at which its
  // own step, cfl (H / 2) / v, is kCflSpeedMargin times the surface's step, no finer; the slow ones keep the
  // vorticity's refinement.
  RestingBlock block(restingBlockScene());
  const SceneDesc& scene = block.scene;
  const Simulation& sim = block.sim;
  ASSERT_TRUE(sim.neighborsValid());
  ParticleSet& p = block.p;
  const Real mFine = sim.latticeMass();
  // a held optimal mass far from every target: the hysteresis keeps none of them
  std::fill(p.mOpt.begin(), p.mOpt.end(), Real(1000) * mFine);
  const Real top = block.top;
  const double shear = 12.0;  // 1/s: between vorticity_lo and vorticity_hi
  const double drift = 0.5;   // m/s
  for (std::size_t i = 0; i < p.size(); ++i)
    p.v[i] = Vec3(Real(drift + shear * double(top - p.x[i].y())), 0, 0);
  SimParams params = scene.params;
  ASSERT_TRUE(params.cflLimitedRefinement);
  std::vector<Real> target;
  LevelEstimator levels;
  levels.compute(p, sim.fluidNeighbors(), sim.boundaryNeighbors(), sim.boundary(), params,
                 AdaptivityMode::FluidPlaying, mFine, target);
  const double r = double(Real(params.particleRadius));
  const double mBase = double(mFine) * params.massRatio;
  // the surface's step: its fastest particle's (phi within surface_distance_lo)
  double surfaceSpeed = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.phi[i] <= Real(params.surfaceDistanceLo * Real(r)))
      surfaceSpeed = std::max(surfaceSpeed, double(p.v[i].norm()));
  }
  const double fineLimit = params.cflFactor * 2.0 * r;
  const double dtSurface = surfaceSpeed > 0 ? std::min(params.dtMax, fineLimit / surfaceSpeed) : params.dtMax;
  int refined = 0, limited = 0, free = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.flags[i] & kFlagSurface)
      continue;
    const double mSurface = optimalMass(p.levelPhi[i], 1.0, 1.0, double(mFine), mBase);
    const double mDynamic = optimalMass(p.levelPhi[i], p.levelOmega[i], p.levelNu[i], double(mFine), mBase);
    if (!(mDynamic < mSurface * (1.0 - 1e-6)))
      continue;  // not refined for its dynamics
    ++refined;
    const double t = double(target[i]);
    const double speed = double(p.v[i].norm());
    // the particle's own step at its target mass, against the surface's
    const double dtOwn = params.cflFactor * 0.5 * double(supportForMass(Real(t), mFine, Real(r))) / speed;
    if (t > mDynamic * (1.0 + 1e-4)) {
      ++limited;
      if (t < mSurface * (1.0 - 1e-4))  // coarsened to its CFL mass, not to the visible level's
        EXPECT_NEAR(dtOwn, kCflSpeedMargin * dtSurface, 1e-3 * dtSurface) << "particle " << i;
      else
        EXPECT_GE(dtOwn, kCflSpeedMargin * dtSurface * (1.0 - 1e-3)) << "particle " << i;
    } else {
      ++free;
      EXPECT_NEAR(t, mDynamic, 1e-4 * mDynamic) << "particle " << i;
      // refined as far as its vorticity asks: it still allows the margin on the surface's step
      EXPECT_GE(dtOwn, kCflSpeedMargin * dtSurface * (1.0 - 1e-3)) << "particle " << i;
    }
  }
  EXPECT_GT(refined, 300);
  EXPECT_GT(limited, 30) << "of " << refined << " refined particles";
  EXPECT_GT(free, 30) << "of " << refined << " refined particles";
}

TEST(LevelsTest, PhiStaysTheExactSurfaceDistanceStepAfterStepSmall) {
  // The same resting block, its levels computed again and again as during a run (after the first call, two
  // Jacobi passes per call): phi must stay the exact distance to the top face at every depth, not drift a hop
  // too far beyond the reach of the passes. (A cap of 16 r: eight layers deep.)
  SceneDesc blockScene = restingBlockScene();
  blockScene.params.surfaceDistanceHi = 16.0;
  RestingBlock block(blockScene);
  const SceneDesc& scene = block.scene;
  const Simulation& sim = block.sim;
  ASSERT_TRUE(sim.neighborsValid());
  ParticleSet& p = block.p;
  const Real r = Real(scene.params.particleRadius);
  const Real top = block.top;
  std::vector<Real> target;
  LevelEstimator levels;
  for (int call = 0; call < 8; ++call)
    levels.compute(p, sim.fluidNeighbors(), sim.boundaryNeighbors(), sim.boundary(), scene.params,
                   AdaptivityMode::FluidPlaying, sim.latticeMass(), target);
  const double cap = scene.params.surfaceDistanceHi * r;
  int checked = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    // away from the side walls, whose particles sit off the lattice
    if (std::abs(p.x[i].x()) > 0.05f || std::abs(p.x[i].z()) > 0.05f || p.x[i].y() < 4 * r)
      continue;
    const double exact = std::min(cap, double(top - p.x[i].y()));
    worst = std::max(worst, std::abs(double(p.phi[i]) - exact));
    ++checked;
  }
  ASSERT_GT(checked, 100);
  EXPECT_LT(worst, 0.2 * r) << "largest |phi - exact distance| in fine radii: " << worst / r;
}

namespace {

/// The collapsing water column the solver and levels tests below share (a 0.2 x 0.3 x 0.2 m block at the end
/// of a 0.6 m tank, r = 8 mm), run in `mode` until `time`, with the neighbour lists of its current positions
std::unique_ptr<Simulation> collapsingColumn(AdaptivityMode mode, double time) {
  SceneDesc scene =
      fp::test::tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0, -0.1), Vec3d(-0.1, 0.3, 0.1), 0.008);
  scene.mode = mode;
  auto sim = std::make_unique<Simulation>(scene);
  while (sim->time() < time)
    sim->step();
  sim->prepareNeighbors();
  return sim;
}

}  // namespace

TEST(LevelsTest, TheDensityPassSumsGiveTheLevelsOfTheirOwnPassSmall) {
  // On the steps that compute the levels the solver's density pass also gathers the raw vorticity and
  // velocity difference (LevelSums), so the levels evaluate no kernel of their own. On a moving adaptive
  // state (a collapsing column, 0.15 s in) the density pass must give the same densities and mean compression
  // with and without the sums, and the levels from the sums those of the levels' own pass: the same surface,
  // omega to round-off, nu and the targets to the difference of the neighbours' volumes (m_j / rho_j at the
  // density before the pass against after it).
  const std::unique_ptr<Simulation> column = collapsingColumn(AdaptivityMode::FluidPlaying, 0.15);
  const Simulation& sim = *column;
  const SceneDesc& scene = sim.scene();
  ASSERT_TRUE(sim.neighborsValid());
  ParticleSet own = sim.particles();
  ParticleSet fused = sim.particles();
  DfsphSolver solverOwn, solverFused;
  SolverContext ctxOwn{own, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), scene.params};
  SolverContext ctxFused{fused, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), scene.params};
  LevelSums sums;
  EXPECT_EQ(solverOwn.computeDensityAndFactor(ctxOwn), solverFused.computeDensityAndFactor(ctxFused, &sums));
  const std::size_t n = own.size();
  ASSERT_TRUE(sums.filled);
  ASSERT_EQ(sums.curl.size(), n);
  ASSERT_EQ(sums.nuSum.size(), n);
  EXPECT_TRUE(sums.rhoBefore.empty());  // needed during the pass only
  for (std::size_t i = 0; i < n; ++i)
    ASSERT_EQ(own.rho[i], fused.rho[i]) << "particle " << i;
  // between the pass and the levels a split child's density may be blended towards its parent's
  // (Adaptivity::blendSplitDensities): the levels finish the sums with the densities they see
  for (std::size_t i = 0; i < n; i += 7) {
    own.rho[i] *= Real(1.03);
    fused.rho[i] *= Real(1.03);
  }
  // the targets are compared without their hysteresis (a held mass far from every target): a target at the
  // edge of its band keeps the held mass on one side and not on the other, whatever the size of the
  // difference that moved it (0.43 of the target for a difference of 1e-3 in nu, measured)
  for (std::size_t i = 0; i < n; ++i) {
    own.mOpt[i] = Real(1e6) * sim.latticeMass();
    fused.mOpt[i] = own.mOpt[i];
  }
  LevelEstimator levelsOwn, levelsFused;
  std::vector<Real> targetOwn, targetFused;
  levelsOwn.compute(own, sim.fluidNeighbors(), sim.boundaryNeighbors(), sim.boundary(), scene.params,
                    scene.mode, sim.latticeMass(), targetOwn);
  levelsFused.compute(fused, sim.fluidNeighbors(), sim.boundaryNeighbors(), sim.boundary(), scene.params,
                      scene.mode, sim.latticeMass(), targetFused, &sums);
  EXPECT_FALSE(sums.filled);  // spent: a later step cannot take them for its own
  double omegaMax = 0.0, nuMax = 0.0, omegaDiff = 0.0, nuDiff = 0.0;
  std::size_t targetsDiffer = 0;
  double targetDiff = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(own.flags[i] & kFlagSurface, fused.flags[i] & kFlagSurface) << "particle " << i;
    omegaMax = std::max(omegaMax, double(own.omega[i]));
    nuMax = std::max(nuMax, double(own.nu[i]));
    omegaDiff = std::max(omegaDiff, std::abs(double(own.omega[i]) - double(fused.omega[i])));
    nuDiff = std::max(nuDiff, std::abs(double(own.nu[i]) - double(fused.nu[i])));
    const double d = std::abs(double(targetOwn[i]) - double(targetFused[i])) / double(targetOwn[i]);
    targetDiff = std::max(targetDiff, d);
    if (d > 1e-4)
      ++targetsDiffer;
  }
  std::printf(
      "%zu particles: omega up to %.3g 1/s (largest difference %.2g), nu up to %.3g m/s (%.2g), %zu "
      "targets differ, by up to %.2g of the target\n",
      n, omegaMax, omegaDiff, nuMax, nuDiff, targetsDiffer, targetDiff);
  // the column moves: the levels see vorticity and velocity differences
  EXPECT_GT(omegaMax, 1.0);
  EXPECT_GT(nuMax, 0.05);
  // measured: omega 5.7e-6 of 25 1/s apart, nu 0.0065 of 0.475 m/s (1.4 %), 14 of 372 targets by up to 4.4 %,
  // well inside the targets' hysteresis band (30 %, sim/levels.cpp)
  EXPECT_LT(omegaDiff, 1e-4 * omegaMax);
  EXPECT_LT(nuDiff, 0.03 * nuMax);
  EXPECT_LT(targetDiff, 0.1);
}

TEST(SolverTest, XsphFromTheDensityPassIsThePairLoopsSmall) {
  // XSPH's neighbour sum comes with the density pass (issue 12: it evaluates every pair's kernel anyway), the
  // pair volume m_j (1 / rho_i + 1 / rho_j) / 2 at the densities before the pass; without that pass the
  // non-pressure forces evaluate it in their pair loop, with m_j / rho_ij. On a moving adaptive state (mixed
  // masses and supports) whose densities are those of now, both give the same accelerations to the
  // difference of the two pair volumes, and the fused sum keeps momentum to round-off.
  const std::unique_ptr<Simulation> column = collapsingColumn(AdaptivityMode::FluidPlaying, 0.15);
  const Simulation& sim = *column;
  const SceneDesc& scene = sim.scene();
  ASSERT_TRUE(sim.neighborsValid());
  SimParams withXsph = scene.params;
  withXsph.viscosity = 0.05;
  SimParams withoutXsph = withXsph;
  withoutXsph.viscosity = 0.0;
  ParticleSet fused = sim.particles();
  ParticleSet loop = sim.particles();
  DfsphSolver solverFused, solverLoop;
  SolverContext fusedOff{fused, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), withoutXsph};
  SolverContext fusedOn{fused, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), withXsph};
  SolverContext loopOff{loop, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), withoutXsph};
  SolverContext loopOn{loop, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), withXsph};
  // the densities of now, so that "before the pass" and "now" are the same densities
  solverFused.computeDensityAndFactor(fusedOff);
  solverLoop.computeDensityAndFactor(loopOff);
  const Real dt = Real(0.002);
  solverFused.computeDensityAndFactor(fusedOn);
  solverFused.nonPressureForces(fusedOn, dt);
  solverLoop.computeDensityAndFactor(loopOff);
  solverLoop.nonPressureForces(loopOn, dt);
  const std::size_t n = fused.size();
  const Vec3 g(Real(scene.params.gravity[0]), Real(scene.params.gravity[1]), Real(scene.params.gravity[2]));
  double largest = 0.0, difference = 0.0, massWeighted = 0.0;
  Vec3d momentum = Vec3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(fused.rho[i], loop.rho[i]);
    const Vec3d a = (loop.a[i] - g).cast<double>();
    const Vec3d b = (fused.a[i] - g).cast<double>();
    largest = std::max(largest, a.norm());
    difference = std::max(difference, (a - b).norm());
    momentum += double(fused.m[i]) * b;
    massWeighted += double(fused.m[i]) * b.norm();
  }
  std::printf(
      "%zu particles: XSPH acceleration up to %.3g m/s^2, fused against the pair loop's %.2g apart at most; "
      "momentum rate %.2g of the sum of |m a|\n",
      n, largest, difference, momentum.norm() / massWeighted);
  // the column moves: XSPH acts
  EXPECT_GT(largest, 1.0);
  // measured: 0.018 of the largest. The pair volumes differ where the neighbours' densities do, at the
  // surface: for rho_i = rho0 / 2 next to rho_j = rho0, (1 / rho_i + 1 / rho_j) / 2 is 1.5 / rho0 and
  // 1 / rho_ij 1.33 / rho0.
  EXPECT_LT(difference, 0.05 * largest);
  EXPECT_LT(momentum.norm(), 1e-5 * massWeighted);
  // a second call has no density pass of its own: the pair loop, from the accelerations it was given
  const ParticleSet once = fused;
  solverFused.nonPressureForces(fusedOn, dt);
  for (std::size_t i = 0; i < n; ++i)
    ASSERT_NEAR((fused.a[i] - loop.a[i]).norm(), 0.0, 1e-4 * largest) << "particle " << i;
  EXPECT_EQ(once.v, fused.v);
}

TEST(SolverTest, XsphTakesADensityOfZeroAsTheRestDensitySmall) {
  // XSPH's pair volumes use the inverse densities before the density pass; a density of zero there (a
  // restored state, never a pass's: a particle's own term is positive) must not turn into infinities: it
  // counts as the rest density, exactly as if that had been stored.
  const std::unique_ptr<Simulation> column = collapsingColumn(AdaptivityMode::UniformHigh, 0.05);
  const Simulation& sim = *column;
  const SceneDesc& scene = sim.scene();
  ASSERT_TRUE(sim.neighborsValid());
  ASSERT_GT(scene.params.viscosity, 0.0);
  ParticleSet zero = sim.particles();
  ParticleSet rest = sim.particles();
  for (std::size_t i = 0; i < zero.size(); i += 3) {
    zero.rho[i] = 0;
    rest.rho[i] = Real(scene.params.restDensity);
  }
  DfsphSolver solverZero, solverRest;
  SolverContext ctxZero{zero, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), scene.params};
  SolverContext ctxRest{rest, sim.boundary(), sim.fluidNeighbors(), sim.boundaryNeighbors(), scene.params};
  solverZero.computeDensityAndFactor(ctxZero);
  solverRest.computeDensityAndFactor(ctxRest);
  solverZero.nonPressureForces(ctxZero, Real(0.002));
  solverRest.nonPressureForces(ctxRest, Real(0.002));
  for (std::size_t i = 0; i < zero.size(); ++i) {
    ASSERT_TRUE(zero.a[i].allFinite()) << "particle " << i;
    ASSERT_EQ(zero.a[i], rest.a[i]) << "particle " << i;
  }
}

TEST(SolverTest, TheFactorPairsEachNeighbourWithBothVolumesSmall) {
  // DFSPH's factor on particles of unequal masses: alpha_i = 1 / (|sum_j V_j grad W_ij + sum_b V_b grad
  // W_ib|^2 + sum_j V_i V_j |grad W_ij|^2). k_i moves a neighbour j by V_i grad W_ij (the pair update is
  // symmetric), so the pair's term is V_i V_j; with it a particle's own stiffness cancels its own density
  // rate when it acts alone. Recomputed here in double precision from that definition for every particle of a
  // jittered block of masses 0.6-4 times the fine mass next to walls; the form with V_j^2 (the uniform
  // formula's) must come out distinguishably different, or the test would not see it return.
  Neighbourhood nb(31);
  SolverContext ctx{nb.p, nb.boundary, nb.fluidNbrs, nb.boundaryNbrs, nb.params};
  DfsphSolver solver;
  solver.computeDensityAndFactor(ctx);
  const ParticleSet& p = nb.p;
  const double invRho0 = 1.0 / nb.params.restDensity;
  const Real Hb = nb.boundary.support();
  double worst = 0.0;
  double largestOtherForm = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double Vi = double(p.m[i]) * invRho0;
    Vec3d gradSum = Vec3d::Zero();
    double pairs = 0.0;
    double pairsOtherForm = 0.0;
    for (std::uint32_t k = nb.fluidNbrs.offsets[i]; k < nb.fluidNbrs.offsets[i + 1]; ++k) {
      const std::uint32_t j = nb.fluidNbrs.neighbor(i, k);
      const Vec3d grad = CubicSpline::grad(p.x[i] - p.x[j], pairSupport(p.H[i], p.H[j])).cast<double>();
      const double Vj = double(p.m[j]) * invRho0;
      gradSum += Vj * grad;
      pairs += Vi * Vj * grad.squaredNorm();
      pairsOtherForm += Vj * Vj * grad.squaredNorm();
    }
    const double sb = double(nb.boundary.volumeScale(p.H[i]));
    for (std::uint32_t k = nb.boundaryNbrs.offsets[i]; k < nb.boundaryNbrs.offsets[i + 1]; ++k) {
      const std::uint32_t b = nb.boundaryNbrs.indices[k];
      gradSum += sb * double(nb.boundary.psi[b]) *
                 CubicSpline::grad(p.x[i] - nb.boundary.x[b], pairSupport(p.H[i], Hb)).cast<double>();
    }
    const double expected = 1.0 / (gradSum.squaredNorm() + pairs);
    const double otherForm = 1.0 / (gradSum.squaredNorm() + pairsOtherForm);
    ASSERT_GT(double(solver.factors()[i]), 0.0) << "particle " << i;
    worst = std::max(worst, std::abs(double(solver.factors()[i]) / expected - 1.0));
    largestOtherForm = std::max(largestOtherForm, std::abs(otherForm / expected - 1.0));
  }
  std::printf(
      "DFSPH factor of %zu particles of unequal masses: largest relative difference %.2g from the "
      "definition (the V_j^2 form differs by up to %.2g)\n",
      p.size(), worst, largestOtherForm);
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(largestOtherForm, 0.1);
}

TEST(AdaptivityTest, MergeLeavesNoSliverOfTheDonorSmall) {
  // A too-light donor whose receivers' rooms add up to its mass only up to round-off: the receivers take all
  // of it and the donor is gone, with mass and momentum kept.
  SimParams params;
  params.particleRadius = 0.01;
  params.transferRate = 1.0;
  const Real r = Real(params.particleRadius);
  const Real mFine = Real(params.restDensity * 8e-6);
  ParticleSet p;
  const Real H = supportForMass(mFine, mFine, r);
  // rooms 0.1, 0.2 and 0.3 m_fine, the donor 0.6 m_fine: 0.1 + 0.2 + 0.3 != 0.6 in floating point
  const Real rooms[] = {0.3f, 0.1f, 0.2f};
  p.add(Vec3::Zero(), Vec3(1, 0, 0), Real(0.6) * mFine, H, 1000.0f);
  p.mOpt[0] = Real(2) * mFine;
  for (int k = 0; k < 3; ++k) {
    // light receivers (m / m_opt between merge_below and light_below)
    const std::size_t j = p.add(Vec3(Real(k + 1) * r, 0, 0), Vec3::Zero(), Real(0.5) * mFine, H, 1000.0f);
    p.mOpt[j] = (Real(0.5) + rooms[k]) * mFine;
  }
  NeighborList fluidNbrs;
  NeighborList boundaryNbrs;
  allPairs(p.size(), fluidNbrs, boundaryNbrs);
  BoundarySet boundary;
  std::vector<ColliderState> colliders;
  const double mass = p.totalMass();
  const Vec3d momentum = p.totalMomentum();
  Adaptivity adaptivity;
  const AdaptivityStats st = adaptivity.adapt(
      AdaptContext{p, fluidNbrs, boundaryNbrs, boundary, colliders, params, mFine, 0.0, 0}, true);
  EXPECT_EQ(st.merges, 1u);
  ASSERT_EQ(p.size(), 3u);
  for (Real m : p.m)
    EXPECT_GE(m, Real(0.5) * mFine);
  EXPECT_NEAR(p.totalMass(), mass, 1e-6 * mass);
  EXPECT_LT((p.totalMomentum() - momentum).norm(), 1e-6 * mass);
}

/// A too-light donor (0.25 m_fine at the origin, moving at (1, 0, 0)) among six receivers of `receiverMass`
/// fine masses, optimal mass m_fine, on the axes at 2r, the k-th (1 + spread k) times that far; adapt() runs
/// one adaptation step over all pairs (r = 0.01 m).
struct DonorAmongSix {
  SimParams params;
  Real mFine = 0;
  ParticleSet p;
  DonorAmongSix(const SimParams& base, Real receiverMass, Real spread) : params(base) {
    params.particleRadius = 0.01;
    const Real r = Real(params.particleRadius);
    mFine = Real(params.restDensity * 8e-6);
    const Real H = supportForMass(mFine, mFine, r);
    p.add(Vec3::Zero(), Vec3(1, 0, 0), Real(0.25) * mFine, H, 1000.0f);
    p.mOpt[0] = mFine;
    for (int k = 0; k < 6; ++k) {
      Vec3 at = Vec3::Zero();
      at[k / 2] = Real(k % 2 == 0 ? 2 : -2) * r * (1 + spread * Real(k));
      const std::size_t j = p.add(at, Vec3(0, Real(k), 0), receiverMass * mFine, H, 1000.0f);
      p.mOpt[j] = mFine;
    }
  }
  AdaptivityStats adapt() {
    NeighborList fluidNbrs;
    NeighborList boundaryNbrs;
    allPairs(p.size(), fluidNbrs, boundaryNbrs);
    BoundarySet boundary;
    std::vector<ColliderState> colliders;
    Adaptivity adaptivity;
    return adaptivity.adapt(
        AdaptContext{p, fluidNbrs, boundaryNbrs, boundary, colliders, params, mFine, 0.0, 0}, true);
  }
};

TEST(AdaptivityTest, AMergeFillsNearlyRightNeighboursUpToTheirOptimalMassSmall) {
  // A too-light donor (q = 0.25) among neighbours at q = 0.95: none is light (q < light_below = 0.9), so with
  // merge_receivers_below = light_below it stays, and it is tried again every step. With the default (1) they
  // take it, none above its optimal mass, mass and momentum kept.
  for (const double receiversBelow : {0.9, 1.0}) {
    SimParams params;
    params.transferRate = 1.0;
    params.mergeReceiversBelow = receiversBelow;
    // six rooms of 0.05 m_fine hold the donor's 0.25
    DonorAmongSix six(params, Real(0.95), 0);
    ParticleSet& p = six.p;
    const Real mFine = six.mFine;
    const double mass = p.totalMass();
    const Vec3d momentum = p.totalMomentum();
    const AdaptivityStats st = six.adapt();
    if (receiversBelow < 1.0) {
      EXPECT_EQ(st.merges, 0u);
      EXPECT_EQ(p.size(), 7u);
      continue;
    }
    EXPECT_EQ(st.merges, 1u);
    ASSERT_EQ(p.size(), 6u);
    for (std::size_t i = 0; i < p.size(); ++i) {
      EXPECT_GE(p.m[i], Real(0.95) * mFine);
      EXPECT_LE(double(p.m[i]), double(p.mOpt[i]) * (1 + 1e-6));
    }
    EXPECT_NEAR(p.totalMass(), mass, 1e-6 * mass);
    EXPECT_LT((p.totalMomentum() - momentum).norm(), 1e-6 * mass);
  }
}

TEST(AdaptivityTest, AnAdaptationPeriodScalesTheTransferRateOnlyUpToACapSmall) {
  // A too-light donor (0.25 m_fine) among six light receivers (0.6 m_fine, optimal m_fine). The transfer rate
  // (0.05 a solver step) times the adaptation period bounds what a receiver takes at once: at period 1 the
  // six rooms of 0.03 cannot hold the donor and the merge waits; at period 2 (0.1) it goes through; at period
  // 100 the rate stays capped at 0.1, so no receiver jumps (uncapped, the nearest took all 0.25 at once, +42
  // %, and the propeller at r = 0.00538 blew up three steps into its first adaptation).
  for (const int period : {1, 2, 100}) {
    SimParams params;
    params.transferRate = 0.05;
    params.adaptationPeriod = period;
    DonorAmongSix six(params, Real(0.6), Real(0.1));  // distinct distances: nearest first
    ParticleSet& p = six.p;
    const Real mFine = six.mFine;
    const double mass = p.totalMass();
    const AdaptivityStats st = six.adapt();
    if (period == 1) {
      EXPECT_EQ(st.merges, 0u);
      EXPECT_EQ(p.size(), 7u);
      continue;
    }
    EXPECT_EQ(st.merges, 1u) << period;
    ASSERT_EQ(p.size(), 6u) << period;
    double largest = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      largest = std::max(largest, double(p.m[i]) / (0.6 * double(mFine)) - 1.0);
    EXPECT_LE(largest, 0.1 + 1e-5) << period;
    EXPECT_GT(largest, 0.05) << period;
    EXPECT_NEAR(p.totalMass(), mass, 1e-6 * mass);
  }
}

TEST(AdaptivityTest, NeighbourListsAreInvalidAfterAStepThatSplitOrMergedSmall) {
  SceneDesc scene;
  scene.params.particleRadius = 0.012;
  scene.mode = AdaptivityMode::FluidPlaying;
  ColliderDesc tank;
  tank.shape = ShapeType::Box;
  tank.container = true;
  tank.halfExtents = Vec3d(0.12, 0.15, 0.12);
  tank.position = Vec3d(0, 0.15, 0);
  scene.colliders.push_back(tank);
  scene.fluid.push_back(FluidBlock{Aabb(Vec3d(-0.12, 0, -0.12), Vec3d(0.12, 0.2, 0.12)), Vec3d(0.5, 0, 0)});
  scene.domain = Aabb(Vec3d(-0.2, -0.05, -0.2), Vec3d(0.2, 0.35, 0.2));
  Simulation sim(scene);
  int changed = 0;
  int unchanged = 0;
  for (int k = 0; k < 60 && (changed == 0 || unchanged == 0); ++k) {
    sim.step();
    const AdaptivityStats& st = sim.lastStep().adaptivity;
    if (st.splits + st.merges > 0) {
      ++changed;
      EXPECT_FALSE(sim.neighborsValid()) << "step " << k;
      EXPECT_TRUE(sim.fluidNeighbors().offsets.empty());
    } else {
      ++unchanged;
      ASSERT_TRUE(sim.neighborsValid()) << "step " << k;
      EXPECT_EQ(sim.fluidNeighbors().offsets.size(), sim.particles().size() + 1);
    }
  }
  EXPECT_GT(changed, 0);
  EXPECT_GT(unchanged, 0);
}

TEST(MetricsTest, HeightPercentileIsWeightedByMassSmall) {
  ParticleSet p;
  // 1000 equal particles at heights 0, 1, ..., 999 mm
  for (int k = 0; k < 1000; ++k)
    p.add(Vec3(0, Real(k) * 1e-3f, 0), Vec3::Zero(), 1.0f, 0.04f, 1000.0f);
  EXPECT_NEAR(heightPercentile(p, 0.999), 0.998, 1e-6);
  EXPECT_NEAR(heightPercentile(p, 0.5), 0.499, 1e-6);
  // one particle of 1000 times the mass at the bottom holds half the water: the percentile drops to the
  // height below which 99.9 % of the mass lies
  p.add(Vec3(0, 0, 0), Vec3::Zero(), 1000.0f, 0.4f, 1000.0f);
  EXPECT_NEAR(heightPercentile(p, 0.999), 0.997, 1e-6);
  // splash counts with its source's mass over n_splash
  SplashParticles splash;
  for (int k = 0; k < 40; ++k) {
    splash.x.push_back(Vec3(0, 2.0f, 0));
    splash.radius.push_back(0.01f);
    splash.source.push_back(999);
  }
  EXPECT_NEAR(heightPercentile(p, 0.999, &splash, 4), 2.0, 1e-6);     // 10 particles' worth above everything
  EXPECT_NEAR(heightPercentile(p, 0.999, &splash, 40), 0.998, 1e-6);  // one particle's worth: below the top
  EXPECT_EQ(heightPercentile(ParticleSet(), 0.999), 0.0);
}

TEST(MetricsTest, SurgeFrontLeavesOutTheMassThrownAheadSmall) {
  ParticleSet p;
  // 1000 equal particles at x = 0, 1, ..., 999 mm, radius 10 mm (H = 40 mm): reaches 10 ... 1009 mm
  for (int k = 0; k < 1000; ++k)
    p.add(Vec3(Real(k) * 1e-3f, 0, 0), Vec3::Zero(), 1.0f, 0.04f, 1000.0f);
  EXPECT_NEAR(surgeFront(p, 0.0), 1.009, 1e-6);     // the farthest particle, at its own radius
  EXPECT_NEAR(surgeFront(p, 0.001), 1.008, 1e-6);   // one particle's mass (0.1 %) beyond: the second
  EXPECT_NEAR(surgeFront(p, 0.0095), 1.000, 1e-6);  // 9.5 particles beyond: the tenth farthest
  // two particles thrown far ahead move the farthest reach, not the front of 0.5 % of the water
  p.add(Vec3(1.5f, 0, 0), Vec3::Zero(), 1.0f, 0.04f, 1000.0f);
  p.add(Vec3(1.4f, 0, 0), Vec3::Zero(), 1.0f, 0.04f, 1000.0f);
  EXPECT_NEAR(surgeFront(p, 0.0), 1.51, 1e-6);
  EXPECT_NEAR(surgeFront(p, 0.005), 1.006, 1e-6);  // 5.01 particles beyond: the two and the top four
  // weighted by mass: one heavy particle of 100 (H = 40 mm * 100^(1/3)), behind the two thrown ahead, is the
  // front for every share from theirs (2 / 1102) up to theirs and its own (102 / 1102)
  p.add(Vec3(1.2f, 0, 0), Vec3::Zero(), 100.0f, 0.04f * std::cbrt(100.0f), 1000.0f);
  const double heavyReach = 1.2 + 0.01 * std::cbrt(100.0);
  EXPECT_NEAR(surgeFront(p, 0.0), 1.51, 1e-6);
  EXPECT_NEAR(surgeFront(p, 0.05), heavyReach, 1e-6);
  EXPECT_NEAR(surgeFront(p, 0.09), heavyReach, 1e-6);
  EXPECT_NEAR(surgeFront(p, 0.093), 1.009,
              1e-6);  // 102.5 of 1102 beyond: the two, the heavy one and one more
  EXPECT_EQ(surgeFront(ParticleSet(), 0.001), 0.0);
}

TEST(MetricsTest, TimeStepHeadroomCountsEachParticlesPowerOfTwoLevel) {
  // cfl_factor 0.4, H = 0.04 m: a particle's own step is 0.4 * 0.02 / speed = 0.008 / speed
  const double dt = 1e-3, cfl = 0.4, dtMax = 5e-3;
  ParticleSet p;
  p.add(Vec3(0, 0, 0), Vec3::Zero(), 1.0f, 0.04f, 1000.0f);  // at rest: own step unbounded
  p.add(Vec3(1, 0, 0), Vec3(0, Real(0.008 / 1.5e-3), 0), 1.0f, 0.04f, 1000.0f);  // own 1.5 dt: level 0
  p.add(Vec3(2, 0, 0), Vec3(Real(0.008 / 4.5e-3), 0, 0), 1.0f, 0.04f, 1000.0f);  // own 4.5 dt: level 2
  const TimeStepHeadroom h = timeStepHeadroom(p, dt, cfl, dtMax);
  // capped: the resting one at level 2 (4 ms <= 5 ms < 8 ms), then 1 and 1/4
  EXPECT_DOUBLE_EQ(h.capped, (0.25 + 1.0 + 0.25) / 3.0);
  // uncapped: the resting one at the deepest level
  EXPECT_DOUBLE_EQ(h.uncapped, (std::ldexp(1.0, -kMaxTimeLevel) + 1.0 + 0.25) / 3.0);
  // the acceleration counts as the CFL counts it: |v + dt a|; this one's own step falls to 1.5 dt
  p.a[0] = Vec3(Real(0.008 / 1.5e-3 / dt), 0, 0);
  EXPECT_DOUBLE_EQ(timeStepHeadroom(p, dt, cfl, dtMax).capped, (1.0 + 1.0 + 0.25) / 3.0);
  // a step at dt_max leaves nothing to gain
  EXPECT_DOUBLE_EQ(timeStepHeadroom(p, dtMax, cfl, dtMax).capped, 1.0);
  EXPECT_DOUBLE_EQ(timeStepHeadroom(ParticleSet(), dt, cfl, dtMax).uncapped, 1.0);
}

TEST(MetricsTest, HeightPercentileSelectsWhatAFullSortGivesSmall) {
  // weighted selection against the sorted cumulative sum, with ties in height and whole-number masses (exact
  // sums, so both reach the target at the same particle), over sizes below and above the selection's cut-off
  std::mt19937 rng(41);
  for (const std::size_t n : {1u, 7u, 33u, 100u, 2000u}) {
    ParticleSet p;
    for (std::size_t i = 0; i < n; ++i) {
      const Real y = Real(int(rng() % 50)) * Real(0.01);  // many equal heights
      p.add(Vec3(0, y, 0), Vec3::Zero(), Real(1 + rng() % 27), Real(0.04), 1000.0f);
    }
    std::vector<std::pair<double, double>> sorted;
    for (std::size_t i = 0; i < n; ++i)
      sorted.emplace_back(double(p.x[i].y()), double(p.m[i]));
    std::sort(sorted.begin(), sorted.end());
    double total = 0.0;
    for (const auto& e : sorted)
      total += e.second;
    for (const double fraction : {0.0, 0.1, 0.5, 0.9, 0.999, 1.0}) {
      double below = 0.0, expected = sorted.back().first;
      for (const auto& e : sorted) {
        below += e.second;
        if (below >= fraction * total) {
          expected = e.first;
          break;
        }
      }
      EXPECT_EQ(heightPercentile(p, fraction), expected) << n << " particles, fraction " << fraction;
    }
  }
}

TEST(DivergenceSolveTest, AFineParticleAmongCoarseOnesIsSolvedASurfaceParticleIsNotSmall) {
  // A block of coarse particles (27 finest masses, spacing 6 r) with one of them split into its 27 fine
  // children (spacing 2 r), all moving towards the centre (compression everywhere). A corner child has 7 fine
  // and 7 coarse neighbours: the old rule (fewer than 20 neighbours) skipped it in the divergence solve
  // although it is inside the water; the volume rule (rho / rho0 >= 0.72) solves it. A particle at the
  // block's top corner stays unsolved. (The middle of a top edge reads 0.72, at the threshold, and the
  // centre of the top face of this perfect lattice 0.85, solved: in a settled tank such surface particles
  // have more than 20 neighbours, and the old rule solved them too.)
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real mFine = restLatticeMass(params, r);
  const Real mCoarse = Real(27) * mFine;
  std::vector<ColliderState> colliders(1);
  colliders[0].desc.shape = ShapeType::Box;
  colliders[0].desc.container = true;
  colliders[0].desc.halfExtents = Vec3d::Constant(0.5);
  BoundarySet boundary;
  boundary.build(colliders, r);
  ParticleSet p;
  const Vec3 velocityScale(Real(-1), Real(-1), Real(-1));
  auto add = [&](const Vec3& x, Real m) {
    p.add(x, velocityScale.cwiseProduct(x), m, supportForMass(m, mFine, r), Real(params.restDensity));
  };
  for (int z = -3; z <= 3; ++z)
    for (int y = -3; y <= 3; ++y)
      for (int x = -3; x <= 3; ++x) {
        if (x != 0 || y != 0 || z != 0)
          add(Real(6) * r * Vec3(Real(x), Real(y), Real(z)), mCoarse);
      }
  const std::size_t firstChild = p.size();
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        add(Real(2) * r * Vec3(Real(x), Real(y), Real(z)), mFine);
  // neighbours within the pair support, both ways; no wall is near
  NeighborList fluidNbrs;
  NeighborList boundaryNbrs;
  fluidNbrs.offsets.push_back(0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = 0; j < p.size(); ++j) {
      if (j != i && (p.x[i] - p.x[j]).norm() < pairSupport(p.H[i], p.H[j]))
        fluidNbrs.indices.push_back(std::uint32_t(j));
    }
    fluidNbrs.offsets.push_back(std::uint32_t(fluidNbrs.indices.size()));
  }
  boundaryNbrs.offsets.assign(p.size() + 1, 0);
  // the corner child at (2r, 2r, 2r) and the coarse particle at the block's top corner
  std::size_t corner = p.size();
  std::size_t top = p.size();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (i >= firstChild && (p.x[i] - Vec3::Constant(Real(2) * r)).norm() < Real(1e-4))
      corner = i;
    if (i < firstChild && (p.x[i] - Vec3::Constant(Real(18) * r)).norm() < Real(1e-4))
      top = i;
  }
  ASSERT_LT(corner, p.size());
  ASSERT_LT(top, p.size());
  EXPECT_LT(fluidNbrs.count(corner), 20u);
  DfsphSolver solver;
  SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params};
  solver.computeDensityAndFactor(ctx);
  const double cornerRatio = double(p.rho[corner]) / params.restDensity;
  const double topRatio = double(p.rho[top]) / params.restDensity;
  std::printf("corner child: %u neighbours, rho / rho0 %.3f; top corner: %u neighbours, rho / rho0 %.3f\n",
              fluidNbrs.count(corner), cornerRatio, fluidNbrs.count(top), topRatio);
  solver.divergenceSolve(ctx, Real(0.001));
  EXPECT_GT(p.kappaV[corner], Real(0)) << "the fine child inside the water was skipped";
  EXPECT_EQ(p.kappaV[top], Real(0)) << "the surface particle was solved";
}

TEST(AdaptivityTest, BallSdfEqualsTheFullMeshDistanceInItsBallSmall) {
  // The split check's signed distance around a parent gives the full distance bit for bit at points around
  // it, outside and inside the blades, and its test "at least c" (which mostly decides from the triangles
  // within reach, without a distance) answers as the distance does, also for c at the distance itself.
  ColliderDesc propeller;
  propeller.name = "propeller";
  propeller.shape = ShapeType::Mesh;
  propeller.mesh = std::make_shared<const TriangleMesh>(
      TriangleMesh::loadObj(FP_SOURCE_DIR "/assets/meshes/propeller.obj"));
  const Aabb box = propeller.mesh->bounds();
  const double size = box.diagonal().norm();
  const std::shared_ptr<const MeshSdfData> data = buildMeshSdfData(*propeller.mesh);
  ASSERT_TRUE(data->allClosed);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int inside = 0;
  int compared = 0;
  int outsideCentres = 0;  // (where atLeast may decide without a distance)
  std::array<int, 2> decided{0, 0};
  for (int b = 0; b < 40; ++b) {
    const Vec3d centre = box.center() + 0.6 * Vec3d(unit(rng) * box.sizes().x(), unit(rng) * box.sizes().y(),
                                                    unit(rng) * box.sizes().z());
    const double radius = 0.02 * size * (1.0 + unit(rng));
    const BallSdf ball(propeller, centre);
    ASSERT_EQ(ball.atCentre(), signedDistanceLocal(propeller, centre));
    outsideCentres += ball.atCentre() > 0.0;
    for (int k = 0; k < 25; ++k) {
      Vec3d d(unit(rng), unit(rng), unit(rng));
      if (d.norm() > 1.0)
        continue;
      const Vec3d q = centre + radius * d;
      // the reference: every component by a pass over all its triangles
      double exact = std::numeric_limits<double>::infinity();
      for (std::size_t c = 0; c < data->components.size(); ++c)
        exact = std::min(exact, componentSdfOverAll(*propeller.mesh, *data, c, q));
      ASSERT_EQ(ball(q), exact) << "ball " << b << " point " << k;
      ASSERT_EQ(signedDistanceLocal(propeller, q), exact) << "ball " << b << " point " << k;
      inside += exact < 0.0;
      ++compared;
      for (const double c : {0.25 * radius, 0.5 * radius, radius, 2.0 * radius, std::abs(exact),
                             std::nextafter(std::abs(exact), 0.0),
                             std::nextafter(std::abs(exact), std::numeric_limits<double>::infinity())}) {
        if (!(c > 0.0))
          continue;
        const bool atLeast = ball.atLeast(q, c);
        ASSERT_EQ(atLeast, exact >= c) << "ball " << b << " point " << k << " c " << c;
        decided[atLeast ? 1 : 0] += 1;
      }
    }
  }
  EXPECT_GT(compared, 400);
  EXPECT_GT(inside, 0);
  EXPECT_GT(outsideCentres, 10);
  EXPECT_GT(decided[0], 200);
  EXPECT_GT(decided[1], 200);
}

TEST(DivergenceSolveTest, SprayThatReachedAWallIsNotThrownBackByTheWarmStart) {
  // Four particles of spray (3 fluid neighbours each) rise against a container's ceiling at 4 m/s. Next to
  // the wall the volume rule solves them (rho / rho0 >= 0.72 with the wall's share), and the stiffness that
  // stops them is large. In the next step they still rise, slowly: the warm start must not apply half the
  // impact's stiffness again (it threw such a particle down at 2.5 m/s in the dam break), it skips particles
  // with fewer than 20 neighbours by count.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real m = restLatticeMass(params, r);
  std::vector<ColliderState> colliders(1);
  colliders[0].desc.shape = ShapeType::Box;
  colliders[0].desc.container = true;
  colliders[0].desc.halfExtents = Vec3d::Constant(0.5);
  BoundarySet boundary;
  boundary.build(colliders, r);
  ParticleSet p;
  const Real y = Real(0.5) - Real(1.1) * r;  // a little closer than the lattice keeps from walls
  for (const Vec3& x : {Vec3(0, y, 0), Vec3(2 * r, y, 0), Vec3(0, y, 2 * r), Vec3(2 * r, y, 2 * r)})
    p.add(x, Vec3(0, 4, 0), m, supportForMass(m, m, r), Real(params.restDensity));
  NeighborList fluidNbrs, boundaryNbrs;
  bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
  ASSERT_LT(fluidNbrs.count(0) + boundaryNbrs.count(0), 20u);
  DfsphSolver solver;
  SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params};
  const Real dt = Real(0.0015);
  solver.computeDensityAndFactor(ctx);
  ASSERT_GE(p.rho[0], Real(0.72 * params.restDensity)) << "the wall does not fill the neighbourhood";
  solver.divergenceSolve(ctx, dt);
  const Real stopped = p.v[0].y();
  ASSERT_GT(p.kappaV[0], Real(0));
  // the next step: still rising, at 0.5 m/s
  for (Vec3& v : p.v)
    v = Vec3(0, Real(0.5), 0);
  solver.computeDensityAndFactor(ctx);
  solver.divergenceSolve(ctx, dt);
  std::printf(
      "spray at the ceiling: %u fluid and %u wall neighbours, rho / rho0 %.2f; 4 m/s -> %.3f m/s, then "
      "0.5 m/s -> %.3f m/s\n",
      fluidNbrs.count(0), boundaryNbrs.count(0), double(p.rho[0]) / params.restDensity, double(stopped),
      double(p.v[0].y()));
  EXPECT_LT(std::abs(stopped), 1.0) << "the solve did not stop the spray at the wall";
  // measured 4 -> 0.80 m/s, then 0.5 -> 0.10 m/s: stopped, not thrown down (-1.10 m/s with the warm start
  // there)
  EXPECT_GT(p.v[0].y(), Real(-0.2));
  EXPECT_LT(p.v[0].y(), Real(0.25));
}

TEST(SolverTest, TheFactorOfAParticleInAPocketIsFlooredSmall) {
  // A particle alone in a pocket of boundary (a cupped palm): the walls' gradients cancel, and the factor's
  // denominator |sum V grad W|^2 + sum_j V_i V_j |grad W_ij|^2, whose second sum has no wall term, collapses
  // to a small share of a full neighbourhood's. Such a particle was given ten to twenty times a normal
  // stiffness and thrown out at 25-35 m/s. The denominator is floored at 0.3 of the same sum of squares with
  // the wall pairs counted: checked here against that definition in double precision, for a particle just off
  // the centre of a hollow ball of radius 2.8 r (the boundary gives it 0.61 of the rest density: not caged),
  // along with the particles of a block resting on a floor, which the floor must leave as they were.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real m = restLatticeMass(params, r);
  const Real H = supportForMass(m, m, r);
  std::vector<ColliderState> colliders(2);
  colliders[0].desc.shape = ShapeType::Sphere;  // a hollow ball around the particle
  colliders[0].desc.radius = 2.8 * r;
  colliders[1].desc.shape = ShapeType::Box;  // a floor far away, under a block of fluid
  colliders[1].desc.halfExtents = Vec3d(0.1, 0.02, 0.1);
  colliders[1].position = Vec3d(0.5, -0.02, 0.0);
  BoundarySet boundary;
  boundary.build(colliders, r);
  ParticleSet p;
  p.add(Vec3(Real(0.002), Real(0.001), 0), Vec3::Zero(), m, H, Real(params.restDensity));  // the pocket
  addRestingBlock(p, m, H, r, Real(params.restDensity));
  NeighborList fluidNbrs, boundaryNbrs;
  bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
  DfsphSolver solver;
  SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params};
  solver.computeDensityAndFactor(ctx);
  const double invRho0 = 1.0 / params.restDensity;
  const Real Hb = boundary.support();
  // (denominator as defined, its floor)
  auto definition = [&](std::size_t i) {
    const double Vi = double(p.m[i]) * invRho0;
    Vec3d gradSum = Vec3d::Zero();
    double pairs = 0.0, wallPairs = 0.0;
    for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
      const std::uint32_t j = fluidNbrs.indices[k];
      const Vec3d grad = CubicSpline::grad(p.x[i] - p.x[j], pairSupport(p.H[i], p.H[j])).cast<double>();
      gradSum += double(p.m[j]) * invRho0 * grad;
      pairs += Vi * double(p.m[j]) * invRho0 * grad.squaredNorm();
    }
    const double sb = double(boundary.volumeScale(p.H[i]));
    for (std::uint32_t k = boundaryNbrs.offsets[i]; k < boundaryNbrs.offsets[i + 1]; ++k) {
      const std::uint32_t b = boundaryNbrs.indices[k];
      const double Vb = sb * double(boundary.psi[b]);
      const Vec3d grad = CubicSpline::grad(p.x[i] - boundary.x[b], pairSupport(p.H[i], Hb)).cast<double>();
      gradSum += Vb * grad;
      wallPairs += Vi * Vb * grad.squaredNorm();
    }
    return std::pair<double, double>(gradSum.squaredNorm() + pairs, 0.3 * (pairs + wallPairs));
  };
  const auto [pocketDenominator, pocketFloor] = definition(0);
  ASSERT_EQ(fluidNbrs.count(0), 0u);
  ASSERT_GT(boundaryNbrs.count(0), 20u);
  // the collapse: the denominator as defined is a small share of the sum of squares with the walls (0.15),
  // and the factor is the floor's
  ASSERT_EQ(solver.caged()[0], 0);
  EXPECT_LT(pocketDenominator, 0.25 * pocketFloor / 0.3);
  EXPECT_NEAR(double(solver.factors()[0]) * pocketFloor, 1.0, 1e-5);
  // the block: every particle as defined, the floor nowhere
  double worst = 0.0;
  std::size_t walled = 0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    const auto [denominator, floor] = definition(i);
    ASSERT_GT(denominator, floor) << "particle " << i;
    walled += boundaryNbrs.count(std::uint32_t(i)) > 0;
    worst = std::max(worst, std::abs(double(solver.factors()[i]) * denominator - 1.0));
  }
  std::printf(
      "pocket: denominator %.3g as defined, floored to %.3g (x%.1f); %zu block particles (%zu at the wall) "
      "as defined to %.2g\n",
      pocketDenominator, pocketFloor, pocketFloor / pocketDenominator, p.size() - 1, walled, worst);
  EXPECT_GT(walled, 30u);
  EXPECT_LT(worst, 1e-5);
}

namespace {

/// A floor, static, under addRestingBlock's block, and a cage of two plates whose faces stand at y = +-0.9 r,
/// within x = +-plateHalfX, moving at `velocity`.
std::vector<ColliderState> floorAndCage(Real r, double plateHalfX, const Vec3d& velocity) {
  std::vector<ColliderState> colliders(3);
  colliders[0].desc.shape = ShapeType::Box;
  colliders[0].desc.halfExtents = Vec3d(0.1, 0.02, 0.1);
  colliders[0].position = Vec3d(0.5, -0.02, 0.0);
  for (int s = 1; s < 3; ++s) {
    ColliderState& c = colliders[std::size_t(s)];
    c.desc.shape = ShapeType::Box;
    c.desc.halfExtents = Vec3d(plateHalfX, 0.02, 0.1);
    c.desc.linearVelocity = velocity;
    c.position = Vec3d(0.0, (s == 1 ? 1.0 : -1.0) * (0.9 * double(r) + 0.02), 0.0);
    c.linearVelocity = velocity;
  }
  return colliders;
}

/// The share of particle i's rest density that its boundary neighbours give, from its definition.
double boundaryShare(const ParticleSet& p, const BoundarySet& boundary, const NeighborList& boundaryNbrs,
                     std::size_t i) {
  double share = 0.0;
  const double sb = double(boundary.volumeScale(p.H[i]));
  for (std::uint32_t k = boundaryNbrs.offsets[i]; k < boundaryNbrs.offsets[i + 1]; ++k) {
    const std::uint32_t b = boundaryNbrs.indices[k];
    share += sb * double(boundary.psi[b]) *
             double(CubicSpline::w((p.x[i] - boundary.x[b]).norm(), pairSupport(p.H[i], boundary.support())));
  }
  return share;
}

}  // namespace

TEST(SolverTest, AParticleCagedByAMovingBoundaryMovesWithItSmall) {
  // Water shut in a closing fist: two particles between two plates 1.8 r apart that move together at 0.4
  // m/s, the boundary alone reading more than 0.8 of their rest density. It cannot lower its density by
  // moving, and the solves made such particles rattle between the walls ever faster (20-55 m/s, or an
  // instability, in the two-hand replay). Caged, it has no stiffness and takes the plates' velocity, the
  // momentum counted as the boundary's; the particles of a block resting on a floor are not caged.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real m = restLatticeMass(params, r);
  const Real H = supportForMass(m, m, r);
  const Vec3d cageVelocity(0.4, -0.1, 0.0);
  const std::vector<ColliderState> colliders = floorAndCage(r, 0.1, cageVelocity);
  BoundarySet boundary;
  boundary.build(colliders, r);
  ASSERT_GT(boundary.size(), boundary.staticCount());
  ParticleSet p;
  p.add(Vec3(Real(0.003), 0, Real(-0.002)), Vec3(0, 3, 0), m, H, Real(params.restDensity));  // caged
  p.add(Vec3(2 * r, 0, 0), Vec3(0, -1, 0), m, H, Real(params.restDensity));  // its one neighbour, caged too
  addRestingBlock(p, m, H, r, Real(params.restDensity));
  NeighborList fluidNbrs, boundaryNbrs;
  bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
  DfsphSolver solver;
  SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params};
  solver.computeDensityAndFactor(ctx);
  // the boundary's share of the caged particle's density, from its definition
  const double share = boundaryShare(p, boundary, boundaryNbrs, 0);
  ASSERT_GE(share, 0.8);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(solver.caged()[i], 1) << "particle " << i;
    EXPECT_EQ(solver.factors()[i], Real(0)) << "particle " << i;
  }
  std::size_t cagedInBlock = 0;
  for (std::size_t i = 2; i < p.size(); ++i) {
    cagedInBlock += solver.caged()[i];
    EXPECT_GT(solver.factors()[i], Real(0)) << "particle " << i;
  }
  EXPECT_EQ(cagedInBlock, 0u);
  const Vec3d momentumBefore =
      double(p.m[0]) * p.v[0].cast<double>() + double(p.m[1]) * p.v[1].cast<double>();
  const Vec3d impulseBefore = solver.boundaryImpulse();
  EXPECT_EQ(solver.carryCaged(ctx), 2u);
  std::printf(
      "caged: the boundary gives %.3f of the rest density; velocity (0, 3, 0) -> (%.3f, %.3f, %.3f) m/s\n",
      share, double(p.v[0].x()), double(p.v[0].y()), double(p.v[0].z()));
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(double(p.v[i].x()), cageVelocity.x(), 1e-6) << "particle " << i;
    EXPECT_NEAR(double(p.v[i].y()), cageVelocity.y(), 1e-6) << "particle " << i;
    EXPECT_NEAR(double(p.v[i].z()), cageVelocity.z(), 1e-6) << "particle " << i;
  }
  for (std::size_t i = 2; i < p.size(); ++i)
    ASSERT_EQ(p.v[i], Vec3::Zero()) << "particle " << i;  // the block is not caged
  // the momentum the fluid gained is the boundary's impulse (to the velocities' single precision)
  const Vec3d momentumAfter = double(p.m[0]) * p.v[0].cast<double>() + double(p.m[1]) * p.v[1].cast<double>();
  const Vec3d impulse = solver.boundaryImpulse() - impulseBefore;
  EXPECT_GT(impulse.norm(), 0.01);
  EXPECT_LT((momentumAfter - momentumBefore - impulse).norm(), 1e-6 * impulse.norm());
}

TEST(SolverTest, AClusterShutInTogetherIsCagedWholeSmall) {
  // Three particles shut in together between two plates 1.8 r apart that move at 0.4 m/s (water in a
  // closing fist: the r = 5 mm replay's seed 35 had four). The outer two read more than 0.8 of their rest
  // density from the plates and under half from their neighbours: caged. The middle one reads more than half
  // from its two neighbours, so that rule leaves it free, and the solves pushed such a particle about like a
  // pinball (to 8.2 m/s in the replay). From the next density pass on its caged neighbours count as cage, and
  // it is caged too. A particle in the air among six flagged as caged is not: the boundary must itself give
  // 0.3 of the rest density. Nor is a block resting on a floor. A cage that opens on one side lets the
  // cluster go within two passes.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real m = restLatticeMass(params, r);
  const Real H = supportForMass(m, m, r);
  const Vec3d cageVelocity(0.4, -0.1, 0.0);
  std::vector<ColliderState> colliders = floorAndCage(r, 4 * double(r), cageVelocity);  // plates to x = +-4 r
  BoundarySet boundary;
  boundary.build(colliders, r);
  const Real d = Real(0.75) * r;  // the clusters' spacing
  const Vec3 air(Real(-0.3), Real(0.3), 0);
  ParticleSet p;
  p.add(Vec3(-d, 0, 0), Vec3(0, 2, 0), m, H, Real(params.restDensity));  // 0-2 in the cage
  p.add(Vec3::Zero(), Vec3(0, -2, 0), m, H, Real(params.restDensity));
  p.add(Vec3(d, 0, 0), Vec3(0, 1, 0), m, H, Real(params.restDensity));
  p.add(air, Vec3(0, -2, 0), m, H, Real(params.restDensity));  // 3 in the air, among six flagged as caged
  for (int axis = 0; axis < 3; ++axis) {
    for (const Real side : {Real(-1), Real(1)}) {
      p.add(air + side * d * Vec3::Unit(axis), Vec3::Zero(), m, H, Real(params.restDensity));
      p.flags.back() |= kFlagCaged;
    }
  }
  addRestingBlock(p, m, H, r, Real(params.restDensity));
  NeighborList fluidNbrs, boundaryNbrs;
  bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
  // the shares of the rest density from the boundary and from the fluid neighbours, by their definitions
  auto shares = [&](std::size_t i) {
    const double fromBoundary = boundaryShare(p, boundary, boundaryNbrs, i);
    double fromFluid = 0.0;
    for (std::uint32_t k = fluidNbrs.offsets[i]; k < fluidNbrs.offsets[i + 1]; ++k) {
      const std::uint32_t j = fluidNbrs.indices[k];
      fromFluid += double(p.m[j]) / params.restDensity *
                   double(CubicSpline::w((p.x[i] - p.x[j]).norm(), pairSupport(p.H[i], p.H[j])));
    }
    return std::pair<double, double>(fromBoundary, fromFluid);
  };
  const auto [outerBoundary, outerFluid] = shares(0);
  const auto [middleBoundary, middleFluid] = shares(1);
  std::printf(
      "cage: the outer particles read %.3f from the plates and %.3f from the fluid, the middle one %.3f "
      "and %.3f\n",
      outerBoundary, outerFluid, middleBoundary, middleFluid);
  ASSERT_GE(outerBoundary, 0.8);
  ASSERT_LT(outerFluid, 0.5);
  ASSERT_GE(middleFluid, 0.5);
  // in the air the flagged neighbours alone give more than 0.8: only the boundary's own 0.3 is missing
  const auto [airBoundary, airFluid] = shares(3);
  ASSERT_EQ(boundaryNbrs.count(3), 0u);
  ASSERT_EQ(airBoundary, 0.0);
  ASSERT_GE(airFluid, 0.8 + 0.1);
  DfsphSolver solver;
  SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params};
  auto cagedOnes = [&] {
    std::vector<std::size_t> caged;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (solver.caged()[i]) {
        caged.push_back(i);
        EXPECT_EQ(solver.factors()[i], Real(0)) << "particle " << i;
      } else {
        EXPECT_GT(solver.factors()[i], Real(0)) << "particle " << i;
      }
    }
    return caged;
  };
  // the first pass: the plates cage the outer two (no one in the cage was caged before it; in the air the
  // flags give no cage without a boundary)
  solver.computeDensityAndFactor(ctx);
  EXPECT_EQ(cagedOnes(), (std::vector<std::size_t>{0, 2}));
  EXPECT_EQ(solver.carryCaged(ctx), 2u);
  for (std::size_t i = 0; i < 10; ++i)
    EXPECT_EQ((p.flags[i] & kFlagCaged) != 0, i == 0 || i == 2) << "particle " << i;
  EXPECT_NEAR(double(p.v[1].y()), -2.0, 1e-6);  // the middle one keeps its own velocity
  // the next pass: the middle one is caged with them
  solver.computeDensityAndFactor(ctx);
  EXPECT_EQ(cagedOnes(), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(solver.caged()[0], 1);  // by the plates alone
  EXPECT_EQ(solver.caged()[1], 2);  // with them
  EXPECT_EQ(solver.caged()[2], 1);
  EXPECT_EQ(solver.carryCaged(ctx), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(double(p.v[i].x()), cageVelocity.x(), 1e-6) << "particle " << i;
    EXPECT_NEAR(double(p.v[i].y()), cageVelocity.y(), 1e-6) << "particle " << i;
    EXPECT_NEAR(double(p.v[i].z()), cageVelocity.z(), 1e-6) << "particle " << i;
  }
  // only the particles that the plates alone cage count as cage in the next pass
  for (std::size_t i = 0; i < 10; ++i)
    EXPECT_EQ((p.flags[i] & kFlagCaged) != 0, i == 0 || i == 2) << "particle " << i;
  EXPECT_NEAR(double(p.v[3].y()), -2.0, 1e-6);  // the particle in the air moves on
  // The cage opens on one side (the lower plate gone): the upper one alone gives each particle about 0.7, and
  // with each other they would read more than 0.8 from "cage". Caged by each other, they would be carried
  // with the plate for good. They may be caged in the first pass, as they still count their neighbours caged
  // in the last step; by the second, no one is.
  colliders.pop_back();
  boundary.build(colliders, r);
  bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
  const auto [oneSideBoundary, oneSideFluid] = shares(0);
  std::printf("one plate: the outer particles read %.3f from it\n", oneSideBoundary);
  ASSERT_GE(oneSideBoundary, 0.6);
  ASSERT_LT(oneSideBoundary, 0.8);
  // the first pass: all three are caged with the two flagged in the last step, none by the plate alone
  solver.computeDensityAndFactor(ctx);
  EXPECT_EQ(cagedOnes(), (std::vector<std::size_t>{0, 1, 2}));
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_EQ(solver.caged()[i], 2) << "particle " << i;
  solver.carryCaged(ctx);
  solver.computeDensityAndFactor(ctx);
  EXPECT_TRUE(cagedOnes().empty());
  EXPECT_EQ(solver.carryCaged(ctx), 0u);
  for (std::size_t i = 0; i < p.size(); ++i)
    EXPECT_EQ(p.flags[i] & kFlagCaged, 0u) << "particle " << i;
}

TEST(SolverTest, StaticWallsCageNoParticleSmall) {
  // A cage moves. Lone particles pressed close to a tank's flat wall (0.3 r and 0.7 r from its particles),
  // edge and corner read 0.8 of their rest density or more from the walls, as do one between two plates 1.8 r
  // apart and one between the tank's wall and a plate 1.8 r from it. With the tank and the plates static,
  // none is caged (static walls cannot close; caged, each would take the walls' zero velocity and hang there
  // for good). With the plates moving and the tank static, the two between a plate and something are caged
  // (the last one's list holds the tank's static particles first, the plate's after them) and those at the
  // tank's walls are not. With the tank moving too, all are: a palm holds what it presses hard enough, the
  // gap that docs/method.md (A cage moves) names.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real m = restLatticeMass(params, r);
  const Real H = supportForMass(m, m, r);
  const char* const names[] = {"static", "plates moving", "all moving"};
  for (int config = 0; config < 3; ++config) {
    const Vec3d velocity(0.0, 0.0, 0.05);
    // a tank with walls at 0 and 0.4 m, as the scenes' (one container); two plates in it (faces at y = 0.2 +-
    // 0.9 r), and one whose face stands 1.8 r from the tank's wall at z = 0.4
    std::vector<ColliderState> colliders(4);
    colliders[0].desc.container = true;
    colliders[0].desc.halfExtents = Vec3d::Constant(0.2);
    colliders[0].position = Vec3d::Constant(0.2);
    for (int s = 1; s < 3; ++s) {
      colliders[std::size_t(s)].desc.halfExtents = Vec3d(0.05, 0.02, 0.05);
      colliders[std::size_t(s)].position =
          Vec3d(0.2, 0.2 + (s == 1 ? 1.0 : -1.0) * (0.9 * double(r) + 0.02), 0.2);
    }
    colliders[3].desc.halfExtents = Vec3d(0.05, 0.05, 0.02);
    colliders[3].position = Vec3d(0.3, 0.3, 0.4 - 1.8 * double(r) - 0.02);
    for (std::size_t c = 0; c < colliders.size(); ++c) {
      colliders[c].desc.shape = ShapeType::Box;
      if (config == 2 || (config == 1 && c > 0)) {
        colliders[c].desc.linearVelocity = velocity;
        colliders[c].linearVelocity = velocity;
      }
    }
    BoundarySet boundary;
    boundary.build(colliders, r);
    if (config == 0)
      ASSERT_EQ(boundary.staticCount(), boundary.size());
    else if (config == 1)
      ASSERT_TRUE(boundary.staticCount() > 0 && boundary.staticCount() < boundary.size());
    else
      ASSERT_EQ(boundary.staticCount(), 0u);
    ParticleSet p;
    const Real mid = Real(0.1);
    p.add(Vec3(Real(0.3) * r, mid, mid), Vec3::Zero(), m, H, Real(params.restDensity));        // wall
    p.add(Vec3(Real(0.7) * r, mid, Real(0.3)), Vec3::Zero(), m, H, Real(params.restDensity));  // wall
    p.add(Vec3(Real(0.6) * r, Real(0.3), Real(0.6) * r), Vec3::Zero(), m, H,
          Real(params.restDensity));                                                             // edge
    p.add(Vec3::Constant(Real(1.2) * r), Vec3::Zero(), m, H, Real(params.restDensity));          // corner
    p.add(Vec3(Real(0.2), Real(0.2), Real(0.2)), Vec3::Zero(), m, H, Real(params.restDensity));  // plates
    p.add(Vec3(Real(0.3), Real(0.3), Real(0.4) - Real(0.9) * r), Vec3::Zero(), m, H,
          Real(params.restDensity));  // the tank's wall and a plate
    NeighborList fluidNbrs, boundaryNbrs;
    bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
    DfsphSolver solver;
    SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params};
    solver.computeDensityAndFactor(ctx);
    for (std::size_t i = 0; i < p.size(); ++i) {
      ASSERT_EQ(fluidNbrs.count(i), 0u) << "particle " << i;
      const double share = boundaryShare(p, boundary, boundaryNbrs, i);
      std::printf("%s: particle %zu, the boundary gives %.3f of the rest density, caged %d\n", names[config],
                  i, share, int(solver.caged()[i]));
      EXPECT_GE(share, 0.83) << "particle " << i;
      const bool cage = config == 2 || (config == 1 && i >= 4);
      EXPECT_EQ(solver.caged()[i], cage ? 1 : 0) << names[config] << ", particle " << i;
      EXPECT_EQ(solver.factors()[i] > Real(0), !cage) << names[config] << ", particle " << i;
    }
  }
}

TEST(SolverTest, AHeldParticleKeepsItsCagedBitThroughTheStepItIsNotEvaluatedSmall) {
  // With time levels, a held particle takes no part in the step's density pass: whether the boundary cages it
  // is not known, so the bit from its last evaluated step stays. A particle evaluated in the step loses it
  // when it is not caged by the boundary alone.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  const Real m = restLatticeMass(params, r);
  const Real H = supportForMass(m, m, r);
  BoundarySet boundary;
  boundary.build({}, r);
  ParticleSet p;
  p.add(Vec3(0, 0, 0), Vec3(0, -1, 0), m, H, Real(params.restDensity));
  p.add(Vec3(Real(0.5), 0, 0), Vec3(0, -1, 0), m, H, Real(params.restDensity));
  for (std::size_t i = 0; i < p.size(); ++i)
    p.flags[i] |= kFlagCaged;
  NeighborList fluidNbrs, boundaryNbrs;
  bruteForceLists(p, boundary, fluidNbrs, boundaryNbrs);
  const std::vector<std::uint8_t> held = {1, 0};
  DfsphSolver solver;
  SolverContext ctx{p, boundary, fluidNbrs, boundaryNbrs, params, held.data(), 1};
  solver.computeDensityAndFactor(ctx);
  ASSERT_EQ(solver.caged()[0], 0);
  ASSERT_EQ(solver.caged()[1], 0);
  EXPECT_EQ(solver.carryCaged(ctx), 0u);
  EXPECT_NE(p.flags[0] & kFlagCaged, 0u);  // held: kept
  EXPECT_EQ(p.flags[1] & kFlagCaged, 0u);  // evaluated, not caged: cleared
  // neither moved with a cage
  EXPECT_EQ(p.v[0], Vec3(0, -1, 0));
  EXPECT_EQ(p.v[1], Vec3(0, -1, 0));
  // the next step evaluates it too: cleared
  SolverContext next{p, boundary, fluidNbrs, boundaryNbrs, params};
  solver.computeDensityAndFactor(next);
  solver.carryCaged(next);
  EXPECT_EQ(p.flags[0] & kFlagCaged, 0u);
}
