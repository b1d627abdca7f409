// Time levels (docs/method.md, Time levels; time_levels = 2): particles whose own CFL step is twice the
// global one, and whose neighbours' is too, skip the solves of every other step and drift. The physics of the
// adaptive tests with the mode on: a tank at rest stays still, a dam break stays bounded and conserves mass,
// and the gravity impulse reaches every particle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sim/simulation.h"
#include "tests/scene_fixtures.h"

using namespace fp::sim;
using fp::test::heldWaterScene;
using fp::test::tankScene;

namespace {

/// Momentum since the start of the budget that neither gravity nor the boundaries account for, as a share of
/// gravity's impulse over that time.
struct MomentumBudget {
  explicit MomentumBudget(const Simulation& sim)
      : mass0(sim.totalMass()), p0(sim.totalMomentum()), t0(sim.time()) {}
  double residual(const Simulation& sim) const {
    const Vec3d gravityImpulse = mass0 * (sim.time() - t0) * Vec3d(0, -9.81, 0);
    return (sim.totalMomentum() - p0 - gravityImpulse - sim.boundaryImpulse()).norm() / gravityImpulse.norm();
  }
  double mass0;
  Vec3d p0;
  double t0;
};

}  // namespace

TEST(TimeLevelsTest, TankAtRestSmallStaysStillWithHeldParticles) {
  // Water at rest alone steps dt_max, and a doubled step would pass it: nothing is held. A sphere spinning in
  // the air above the water (3.7 m/s at its surface, 5 cm clear of it) sets the step instead, at about 2 ms,
  // as a hand does: the water at rest may then take every other step.
  const SceneDesc scene = heldWaterScene();
  Simulation sim(scene);
  const double mass0 = sim.totalMass();
  while (sim.time() < 1.0)
    sim.step();
  const RunStats& run = sim.runStats();
  const double held = double(run.heldParticleSteps) / double(run.particleSteps);
  const ParticleSet& p = sim.particles();
  std::vector<double> heights;
  double e = 0.0;
  int thrown = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    heights.push_back(double(p.x[i].y()));
    e += 0.5 * double(p.m[i]) * double(p.v[i].squaredNorm());
    thrown += double(p.x[i].y()) > 0.33 ? 1 : 0;
  }
  std::sort(heights.begin(), heights.end());
  const double top = heights.back();
  // the level: the 99th percentile of the heights (a single particle thrown up is not the surface)
  const double level = heights[heights.size() * 99 / 100];
  const double vrms = std::sqrt(2.0 * e / mass0);
  std::printf(
      "tank at rest, time_levels = 2: %.1f %% of particle-steps held, %.1f %% on level 1, level %.4f m, top "
      "%.4f m (%d above 0.33 m), rms speed %.4f m/s, mean density error %.3f %%\n",
      100.0 * held, 100.0 * double(run.level1ParticleSteps) / double(run.particleSteps), level, top, thrown,
      vrms, 100.0 * run.densityErrorSum / double(run.steps));
  EXPECT_GT(held, 0.2);
  EXPECT_NEAR(sim.totalMass(), mass0, 1e-6 * mass0);
  // measured: level 0.2948 m, top 0.3405 m (one particle of 504, since merges fill nearly right neighbours;
  // 0.2988 m before); level 0.3022 m, top 0.3400 m, then with the symmetric search's lists left in two
  // ascending parts (the sums' order: rounding) 0.2992 m and 0.3819 m, one droplet. As in
  // AdaptivePhysicsTest.TankAtRestStaysStillFineAtTheSurfaceCoarseInside: the level, at most a few droplets
  // above 0.33 m, none far.
  EXPECT_NEAR(level, 0.3, 0.03);
  EXPECT_LE(thrown, 3) << thrown << " particles above 0.33 m";
  EXPECT_LT(top, 0.4);
  EXPECT_LT(vrms, 0.3);
}

TEST(TimeLevelsTest, DamBreakSmallBoundedConservingMassAndGravityImpulse) {
  SceneDesc scene = tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0.0, -0.1), Vec3d(-0.05, 0.3, 0.1), 0.008);
  scene.mode = AdaptivityMode::FluidPlaying;
  scene.params.timeLevels = 2;
  Simulation sim(scene);
  const double mass0 = sim.totalMass();
  const MomentumBudget budget(sim);
  while (sim.time() < 1.0)
    ASSERT_NO_THROW(sim.step());
  const RunStats& run = sim.runStats();
  EXPECT_GT(run.heldParticleSteps, 0u);
  EXPECT_NEAR(sim.totalMass(), mass0, 1e-6 * mass0);
  // Held particles take the reaction of their active neighbours' pressure, and the gravity of the held step
  // comes with the next one; XSPH across the interface is one-sided in a held step, so momentum is conserved
  // to a few 1e-3, not to round-off as with one time step (2.2e-2 without the reaction). The figure depends
  // on the trajectory: with the targets' hysteresis (session 6) this run gives 1.1e-4 in the Release build
  // and 2.1e-3 in the ASan+UBSan build (the same code, other rounding), so the bound is 5e-3.
  const double residual = budget.residual(sim);
  std::printf(
      "dam break, time_levels = 2: %.1f %% of particle-steps held; momentum residual %.2e of the "
      "gravity impulse\n",
      100.0 * double(run.heldParticleSteps) / double(run.particleSteps), residual);
  EXPECT_LT(residual, 5e-3);
  for (const Vec3& x : sim.particles().x) {
    EXPECT_GE(x.y(), 0.0f);
    EXPECT_LE(std::abs(x.x()), 0.3f);
  }
}

TEST(TimeLevelsTest, HeldParticlesSmallDoNotStallTheDensitySolve) {
  // A held particle keeps the density it was held with; the solve does not correct it, so its error must
  // not count in the solve's mean. It did: in the deep water of a dam break the held particles' compression
  // alone stood above the tolerance, and every held step ran to max_iterations (the reference dam break:
  // 49 density iterations a step on average against 4.0 with one time step, and 27 % more wall time).
  SceneDesc scene = tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0.0, -0.1), Vec3d(-0.05, 0.3, 0.1), 0.008);
  scene.mode = AdaptivityMode::UniformHigh;
  auto run = [&](int levels) {
    SceneDesc s = scene;
    s.params.timeLevels = levels;
    Simulation sim(s);
    while (sim.time() < 0.5)
      sim.step();
    return sim.runStats();
  };
  const RunStats one = run(1);
  const RunStats two = run(2);
  const double itersOne = double(one.densityIterations) / double(one.steps);
  const double itersTwo = double(two.densityIterations) / double(two.steps);
  const double held = double(two.heldParticleSteps) / double(two.particleSteps);
  std::printf(
      "dam break, uniform: density iterations a step %.2f (one time step) against %.2f (time_levels = 2, "
      "%.1f %% of particle-steps held); steps %llu against %llu\n",
      itersOne, itersTwo, 100.0 * held, (unsigned long long)one.steps, (unsigned long long)two.steps);
  EXPECT_GT(held, 0.1);
  EXPECT_LT(itersTwo, itersOne + 1.0);
  EXPECT_LT(itersTwo, 0.2 * double(scene.params.maxIterations));
}

TEST(TimeLevelsTest, SwitchedOffLiveAfterAHeldStepSmallStillGivesItsGravity) {
  // time_levels is live (the panel): set to 1 right after a held step, the next step must still give the held
  // particles the gravity impulse they drifted without
  SceneDesc scene = tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0.0, -0.1), Vec3d(-0.05, 0.3, 0.1), 0.008);
  scene.mode = AdaptivityMode::UniformHigh;
  scene.params.timeLevels = 2;
  Simulation sim(scene);
  const MomentumBudget budget(sim);
  bool switched = false;
  while (sim.time() < 0.3) {
    sim.step();
    if (!switched && sim.time() > 0.15 && sim.lastStep().heldParticles > 0) {
      sim.params().timeLevels = 1;
      switched = true;
    }
  }
  ASSERT_TRUE(switched);
  const double residual = budget.residual(sim);
  std::printf("switched off after a held step: momentum residual %.2e of the gravity impulse\n", residual);
  // one step's gravity of the held particles is about 1e-3 of the impulse over 0.3 s
  EXPECT_LT(residual, 2e-4);
}
