// Temporal blending after a split (docs/method.md, Adaptivity): a split child's velocity and density are
// blended from its parent's for split_blend_steps solver steps. Measured on one state split both ways: the
// same simulation copied right after a step that split, one copy with blending and one without.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

#include "sim/adaptivity.h"
#include "sim/kernels.h"
#include "sim/levels.h"
#include "sim/simulation.h"
#include "tests/scene_fixtures.h"

using namespace fp::sim;
using fp::test::tankScene;

TEST(SplitBlendingTest, VelocityBlendConservesMomentumAndPullsSiblingsTogether) {
  ParticleSet p;
  SimParams params;
  params.splitBlendSteps = 10;
  const Real rho0 = Real(params.restDensity);
  // two groups of siblings (parents 7 and 9) and one particle that does not blend
  p.add(Vec3(0, 0, 0), Vec3(1, 0, 0), 1.0f, 0.1f, rho0);
  p.add(Vec3(0.01f, 0, 0), Vec3(-1, 0.5f, 0), 2.0f, 0.1f, rho0);
  p.add(Vec3(0.5f, 0, 0), Vec3(0, 0, 3), 1.0f, 0.1f, rho0);
  p.add(Vec3(0.51f, 0, 0), Vec3(0, 0, -1), 1.0f, 0.1f, rho0);
  p.add(Vec3(1, 0, 0), Vec3(2, 2, 2), 1.0f, 0.1f, rho0);
  p.parentId = {7, 7, 9, 9, kNoParent};
  p.splitAge = {0, 0, 5, 5, 0};
  const Vec3d before = p.totalMomentum();
  Adaptivity::blendSplitVelocities(p, params);
  EXPECT_LT((p.totalMomentum() - before).norm(), 1e-6);
  // age 0: half way to the group's mean velocity (-1/3, 1/3, 0)
  EXPECT_NEAR(p.v[0].x(), 0.5 * (1.0 - 1.0 / 3.0), 1e-6);
  EXPECT_NEAR(p.v[0].y(), 0.5 * (1.0 / 3.0), 1e-6);
  // age 5 of 10: a quarter of the way to (0, 0, 1)
  EXPECT_NEAR(p.v[2].z(), 3.0 - 0.25 * 2.0, 1e-6);
  EXPECT_EQ(p.v[4], Vec3(2, 2, 2));
  EXPECT_FLOAT_EQ(Adaptivity::splitBlendWeight(0, 10), 0.5f);
  EXPECT_FLOAT_EQ(Adaptivity::splitBlendWeight(10, 10), 0.0f);
  EXPECT_FLOAT_EQ(Adaptivity::splitBlendWeight(0, 0), 0.0f);
  // ageing ends the blending after split_blend_steps steps
  for (int k = 0; k < 5; ++k)
    Adaptivity::ageSplitChildren(p, params);
  EXPECT_EQ(p.parentId[0], 7u);
  EXPECT_EQ(p.parentId[2], kNoParent);
  EXPECT_EQ(p.parentId[4], kNoParent);
}

TEST(SplitBlendingTest, TheParentsDensityCountsEveryParticleWithinItsSupportSmall) {
  // Three siblings of nine fine masses each next to a wall of a box of fine water: the parent (27 fine
  // masses, support 12 r) reaches further than the siblings' own supports (4 r 9^(1/3) = 8.3 r), so a parent
  // summed over the siblings' own neighbours misses its outer shell. The blended density must be the one of
  // the whole support: every fluid particle but the siblings and every wall particle within the parent's pair
  // support of the siblings' centre of mass, the container's walls and a moving sphere's particles alike.
  // Every sibling moves half way to it (age 0), the denser one down.
  const Real r = Real(0.01);
  SimParams params;
  params.particleRadius = r;
  params.splitBlendSteps = 10;
  const double rho0 = params.restDensity;
  const Real mFine = Real(rho0 * 8.0 * double(r) * r * r);
  std::vector<ColliderState> colliders(1);
  colliders[0].desc.shape = ShapeType::Box;
  colliders[0].desc.container = true;
  colliders[0].desc.halfExtents = Vec3d::Constant(0.1);
  // a driven sphere in the water near the siblings: moving boundary particles, after the static ones
  ColliderState ball;
  ball.desc.shape = ShapeType::Sphere;
  ball.desc.radius = 0.02;
  ball.desc.driven = true;
  ball.desc.position = ball.position = Vec3d(0.04, 0.045, 0.0);
  colliders.push_back(ball);
  BoundarySet boundary;
  boundary.build(colliders, r);
  ParticleSet p;
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> jitter(-0.2f * r, 0.2f * r);
  for (int z = -4; z <= 4; ++z)
    for (int y = -4; y <= 4; ++y)
      for (int x = -4; x <= 4; ++x)
        p.add(Real(2) * r * Vec3(Real(x), Real(y), Real(z)) + Vec3(jitter(rng), jitter(rng), jitter(rng)),
              Vec3::Zero(), mFine, supportForMass(mFine, mFine, r), Real(rho0));
  // the siblings: the three particles nearest a point one spacing from the wall at x = 0.1 m
  const Vec3 at(Real(0.08), Real(0.0), Real(0.0));
  std::vector<std::size_t> byDistance(p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    byDistance[i] = i;
  std::sort(byDistance.begin(), byDistance.end(),
            [&](std::size_t a, std::size_t b) { return (p.x[a] - at).norm() < (p.x[b] - at).norm(); });
  const std::uint32_t parent = 100000;
  const Real densities[] = {Real(900), Real(950), Real(1700)};
  for (int k = 0; k < 3; ++k) {
    // (nine fine masses each, with the support of that mass: the siblings of a split base particle whose
    // supports have shrunk to their own)
    p.m[byDistance[std::size_t(k)]] = Real(9) * mFine;
    p.H[byDistance[std::size_t(k)]] = supportForMass(Real(9) * mFine, mFine, r);
    p.parentId[byDistance[std::size_t(k)]] = parent;
    p.splitAge[byDistance[std::size_t(k)]] = 0;  // (weight 0.5)
    p.rho[byDistance[std::size_t(k)]] = densities[k];
  }
  // sorted into a grid as the step's search sorts them
  UniformGrid grid;
  grid.setup(Aabb(Vec3d::Constant(-0.15), Vec3d::Constant(0.15)), Real(4) * r);
  std::vector<std::uint32_t> order, fluidCells, staticCells, kinematicCells;
  const std::size_t nStatic = boundary.staticCount();
  ASSERT_GT(boundary.size(), nStatic);
  grid.sort(boundary.x.data(), nStatic, order, staticCells);
  boundary.permute(0, order);
  grid.sort(boundary.x.data() + nStatic, boundary.size() - nStatic, order, kinematicCells);
  boundary.permute(nStatic, order);
  grid.sort(p.x.data(), p.size(), order, fluidCells);
  p.permute(order);
  std::vector<std::size_t> members;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.parentId[i] == parent)
      members.push_back(i);
  }
  ASSERT_EQ(members.size(), 3u);
  // the parent's density, summed over every particle
  double mass = 0.0;
  Vec3d centre = Vec3d::Zero();
  for (std::size_t s : members) {
    mass += double(p.m[s]);
    centre += double(p.m[s]) * p.x[s].cast<double>();
  }
  centre /= mass;
  const Vec3 xo = centre.cast<Real>();
  const Real Ho = supportForMass(Real(mass), mFine, r);
  double density = mass / rho0 * double(CubicSpline::w0(Ho));
  int outerShell = 0;  // within the parent's reach, beyond every sibling's own
  double shell = 0.0;  // their share of the parent's density [-]
  for (std::size_t j = 0; j < p.size(); ++j) {
    if (std::find(members.begin(), members.end(), j) != members.end())
      continue;
    const Real d = (xo - p.x[j]).norm();
    const double term = double(p.m[j]) / rho0 * double(CubicSpline::w(d, pairSupport(Ho, p.H[j])));
    density += term;
    bool seen = false;
    for (std::size_t s : members)
      seen |= (p.x[s] - p.x[j]).norm() < pairSupport(p.H[s], p.H[j]);
    if (d < pairSupport(Ho, p.H[j]) && !seen) {
      ++outerShell;
      shell += term;
    }
  }
  const Real Hob = pairSupport(Ho, boundary.support());
  int walls = 0, moving = 0;
  for (std::size_t b = 0; b < boundary.size(); ++b) {
    const Real d = (xo - boundary.x[b]).norm();
    density += double(boundary.volumeScale(Ho)) * double(boundary.psi[b]) * double(CubicSpline::w(d, Hob));
    walls += d < Hob && b < nStatic ? 1 : 0;
    moving += d < Hob && b >= nStatic ? 1 : 0;
  }
  const double rhoParent = density * rho0;
  std::printf(
      "parent density %.2f kg/m^3, %.2f of it from %d fluid particles beyond the siblings' reach; %d wall "
      "and "
      "%d moving boundary particles\n",
      rhoParent, shell * rho0, outerShell, walls, moving);
  // the shell the siblings' own neighbours miss weighs far more than the tolerance below
  ASSERT_GT(outerShell, 0);
  ASSERT_GT(0.5 * shell * rho0, 1.0);
  ASSERT_GT(walls, 0);
  ASSERT_GT(moving, 0);
  std::vector<Real> before(p.rho);
  const Real maxH = *std::max_element(p.H.begin(), p.H.end());
  Adaptivity::blendSplitDensities(p, {grid, fluidCells, staticCells, kinematicCells, maxH}, boundary, params,
                                  mFine);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.parentId[i] == parent)  // half way to the parent's density (age 0)
      EXPECT_NEAR(double(p.rho[i]), double(before[i]) + 0.5 * (rhoParent - double(before[i])), 0.01) << i;
    else
      EXPECT_EQ(p.rho[i], before[i]) << i;
  }
  // cell ranges of other particles than these blend nothing
  std::vector<Real> after(p.rho);
  const std::vector<std::uint32_t> none;
  Adaptivity::blendSplitDensities(p, {grid, none, staticCells, kinematicCells, maxH}, boundary, params,
                                  mFine);
  EXPECT_EQ(p.rho, after);
}

TEST(SplitBlendingTest, ChildrenStartCloserToTheirParentWithBlending) {
  SceneDesc scene = tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0.0, -0.1), Vec3d(-0.05, 0.3, 0.1), 0.008);
  scene.mode = AdaptivityMode::FluidPlaying;
  scene.params.splitBlendSteps = 10;  // off by default (docs/method.md, Temporal blending)
  Simulation blended(scene);
  // the first step from 0.1 s on that splits a few particles
  while (blended.time() < 0.1 || blended.lastStep().adaptivity.splits < 3)
    blended.step();
  Simulation plain = blended;
  plain.params().splitBlendSteps = 0;
  // the children of this step's splits (age 0) by id: the parent's id, density and velocity (inherited)
  struct Child {
    std::uint32_t parent;
    Real rho;
    Vec3 v;
  };
  std::map<std::uint32_t, Child> children;
  const ParticleSet& p0 = blended.particles();
  for (std::size_t i = 0; i < p0.size(); ++i) {
    if (p0.parentId[i] != kNoParent && p0.splitAge[i] == 0)
      children[p0.id[i]] = Child{p0.parentId[i], p0.rho[i], p0.v[i]};
  }
  ASSERT_GE(children.size(), 6u);
  // per step: mean |rho_s - rho_parent| / rho0 (the densities the solver used) and the rms deviation of the
  // children's velocities from their siblings' mean, for the blended and the plain copy
  const double rho0 = scene.params.restDensity;
  double jump[2][3] = {}, spread[2][3] = {};
  Simulation* sims[2] = {&blended, &plain};
  for (int step = 0; step < 3; ++step) {
    for (int k = 0; k < 2; ++k) {
      sims[k]->step();
      const ParticleSet& p = sims[k]->particles();
      std::map<std::uint32_t, std::pair<double, Vec3d>> groups;  // parent: mass, momentum
      std::vector<std::size_t> found;
      for (std::size_t i = 0; i < p.size(); ++i) {
        const auto c = children.find(p.id[i]);
        if (c == children.end())
          continue;
        found.push_back(i);
        auto& g = groups.try_emplace(c->second.parent, 0.0, Vec3d::Zero()).first->second;
        g.first += double(p.m[i]);
        g.second += double(p.m[i]) * p.v[i].cast<double>();
        jump[k][step] += std::abs(double(p.rho[i]) - double(c->second.rho)) / rho0;
      }
      ASSERT_EQ(found.size(), children.size());
      for (std::size_t i : found) {
        const auto& g = groups[children[p.id[i]].parent];
        spread[k][step] += (p.v[i].cast<double>() - g.second / g.first).squaredNorm();
      }
      jump[k][step] /= double(found.size());
      spread[k][step] = std::sqrt(spread[k][step] / double(found.size()));
    }
  }
  for (int step = 0; step < 3; ++step) {
    std::printf(
        "  step %d after %zu children: density jump against the parent %.3f %% (blended) %.3f %% (plain), "
        "sibling velocity spread %.4f m/s (blended) %.4f m/s (plain)\n",
        step + 1, children.size(), 100.0 * jump[0][step], 100.0 * jump[1][step], spread[0][step],
        spread[1][step]);
  }
  // the first step's densities are half way to the parent's
  EXPECT_LT(jump[0][0], 0.75 * jump[1][0]);
  // the siblings move together more closely
  EXPECT_LE(spread[0][2], spread[1][2]);
}
