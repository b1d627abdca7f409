// Temporal blending after a split (docs/method.md, Adaptivity): a split child's velocity and density are
// blended from its parent's for split_blend_steps solver steps. Measured on one state split both ways: the
// same simulation copied right after a step that split, one copy with blending and one without.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "sim/adaptivity.h"
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
