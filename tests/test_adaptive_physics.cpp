// The adaptive modes on whole scenes: a tank at rest keeps still with fine particles at its surface and
// coarse ones inside, the propeller draws fine particles into its vortices (unlike surface-only adaptivity),
// a long run keeps its particle count bounded and its mass and momentum, and runs are deterministic. Tests
// named *Small* also run under the sanitizers in CI.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <numeric>
#include <string>
#include <vector>

#include "engine/scene_loader.h"
#include "sim/metrics.h"
#include "sim/simulation.h"
#include "tests/scene_fixtures.h"

using namespace fp::sim;
using fp::test::tankScene;

namespace {

/// mean mass, in finest masses, of the particles selected by `pick`
template <class F>
double meanMassRatio(const Simulation& sim, F&& pick) {
  double sum = 0.0;
  int count = 0;
  const ParticleSet& p = sim.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (pick(i)) {
      sum += double(p.m[i]) / double(sim.latticeMass());
      ++count;
    }
  }
  return count ? sum / count : 0.0;
}

}  // namespace

TEST(AdaptivePhysicsTest, TankAtRestStaysStillFineAtTheSurfaceCoarseInside) {
  SceneDesc scene = tankScene(Vec3d(0.2, 0.2, 0.2), Vec3d(-0.2, 0.0, -0.2), Vec3d(0.2, 0.3, 0.2), 0.2 / 20.4);
  scene.mode = AdaptivityMode::FluidPlaying;
  SceneDesc uniform = scene;
  uniform.mode = AdaptivityMode::UniformHigh;
  const std::size_t nHigh = Simulation(uniform).particles().size();
  Simulation sim(scene);
  const double mass0 = sim.totalMass();
  double errorSum = 0.0;
  double vrmsSum = 0.0;
  int steps = 0;
  while (sim.time() < 1.5) {
    sim.step();
    if (sim.time() > 1.0) {
      errorSum += sim.lastStep().densityError;
      double e = 0.0;
      for (std::size_t i = 0; i < sim.particles().size(); ++i)
        e += double(sim.particles().m[i]) * double(sim.particles().v[i].squaredNorm());
      vrmsSum += std::sqrt(e / mass0);
      ++steps;
    }
  }
  const ParticleSet& p = sim.particles();
  EXPECT_NEAR(sim.totalMass(), mass0, 1e-6 * mass0);
  EXPECT_LT(errorSum / steps, 0.005);
  // still: the water surface stays level (the 99th percentile of the heights: the highest particle alone
  // follows the one droplet the restless fine particles may throw, 0.29-0.34 m over six seeds and a
  // rounding-level change of the levels; the percentile 0.287-0.294 m), at most a few droplets above it
  // (0 or 1 above 0.33 m over those runs), none far, and the kinetic energy small
  std::vector<double> heights;
  int thrown = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    heights.push_back(double(p.x[i].y()));
    thrown += double(p.x[i].y()) > 0.33 ? 1 : 0;
  }
  std::sort(heights.begin(), heights.end());
  const double level = heights[std::size_t(0.99 * double(heights.size()))];
  EXPECT_NEAR(level, 0.3, 0.02);
  EXPECT_LE(thrown, 3) << thrown << " particles above 0.33 m";
  EXPECT_LT(heights.back(), 0.4) << "the highest particle";
  // the rms speed averaged over the last 0.5 s: measured 0.113 m/s (the fastest particle at 1.5 s at 0.57
  // m/s); bound 0.145 (1.28x; it was 0.3 at one instant)
  const double vrms = vrmsSum / steps;
  double vmax = 0.0;
  for (const Vec3& v : p.v)
    vmax = std::max(vmax, double(v.norm()));
  std::printf(
      "adaptive tank at rest from 1 s to 1.5 s: rms speed %.4f m/s (at 1.5 s: max %.4f m/s), %zu particles "
      "of %zu\n",
      vrms, vmax, p.size(), nHigh);
  EXPECT_LT(vrms, 0.145) << "rms speed " << vrms << " m/s";
  // finest at the surface, coarse at the bottom, and far fewer particles than uniform-high
  // (the free-surface particles: with surface_distance_lo = 0 only they are fully fine)
  const double atSurface =
      meanMassRatio(sim, [&](std::size_t i) { return (p.flags[i] & kFlagSurface) != 0; });
  const double atBottom = meanMassRatio(sim, [&](std::size_t i) { return p.x[i].y() < 0.08; });
  EXPECT_LT(atSurface, 1.5);
  EXPECT_GT(atBottom, 6.0);
  EXPECT_LT(double(p.size()), 0.6 * double(nHigh)) << p.size() << " of " << nHigh;
}

// The desktop's resting tank (issue 14, docs/method.md "The adaptive tank at rest"): once settled, the
// resolution stops churning and the water does not stand high. Before the hysteresis of the targets
// (kTargetBand, sim/levels.cpp) the coarse tank ran 4.5 splits and merges and 45 shares a step from 1 s to
// 1.5 s and the surface stood 7.3 mm above uniform-high's.
namespace {

struct RestingTank {
  double splitsMerges = 0;  ///< a step, from 1 s to 1.5 s
  double shares = 0;        ///< a step, from 1 s to 1.5 s
  double above = 0;         ///< mean surface from 1 s to 1.5 s above uniform-high's at 1.5 s [m]
  std::size_t particles = 0;
};

RestingTank restingTank(const std::string& file, double uniformHighSurface) {
  SceneDesc scene = fp::engine::loadScene(std::string(FP_SOURCE_DIR) + "/assets/scenes/" + file);
  scene.mode = AdaptivityMode::FluidPlaying;
  Simulation sim(scene);
  const double mass0 = sim.totalMass();
  const double r = scene.params.particleRadius;
  // the free surface in the middle of the tank: the mean height of the 6th-200th highest particles, plus r
  auto surface = [&] {
    const ParticleSet& p = sim.particles();
    std::vector<double> ys;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (std::abs(p.x[i].x()) < 0.2 && std::abs(p.x[i].z()) < 0.12)
        ys.push_back(double(p.x[i].y()));
    }
    std::sort(ys.begin(), ys.end(), std::greater<double>());
    double sum = 0.0;
    int count = 0;
    for (std::size_t k = 5; k < 200 && k < ys.size(); ++k, ++count)
      sum += ys[k];
    return sum / std::max(1, count) + r;
  };
  AdaptivityStats ops;
  int steps = 0;
  double surfaceSum = 0.0;
  while (sim.time() < 1.5) {
    sim.step();
    if (sim.time() > 1.0) {
      ops += sim.lastStep().adaptivity;
      surfaceSum += surface();
      ++steps;
    }
  }
  EXPECT_GT(steps, 0);
  EXPECT_NEAR(sim.totalMass(), mass0, 1e-6 * mass0);
  RestingTank t;
  t.splitsMerges = double(ops.splits + ops.merges) / std::max(1, steps);
  t.shares = double(ops.redistributions) / std::max(1, steps);
  t.above = surfaceSum / std::max(1, steps) - uniformHighSurface;
  t.particles = sim.particles().size();
  std::printf(
      "%s at rest, 1 s to 1.5 s: %.2f splits and merges, %.1f shares a step; surface %.1f mm above "
      "uniform-high's; %zu particles\n",
      file.c_str(), t.splitsMerges, t.shares, 1000.0 * t.above, t.particles);
  return t;
}

}  // namespace

TEST(AdaptivePhysicsTest, HandTankAtRestStopsChurningAndStandsNearUniformHigh) {
  // r = 7.9 mm; uniform-high's surface there at 1.5 s: 0.1307 m from its settled start (0.1308 m from the
  // bare lattice before session 16; deterministic, a run of 5984 particles)
  const RestingTank t = restingTank("hand_tank_coarse.json", 0.1307);
  // measured 1.64 and 13.5 in session 15 (bounds 2.5 and 30; 1.93 and 15.4 in an earlier session);
  // the surface 6.7 mm above (6.8 mm above the settled uniform-high of session 16; bound 7 mm: 5.5 mm when
  // the hysteresis came, 7.3 mm before it; 6.4 mm on cd6cdab, before the divergence solve's warm start
  // skipped particles with fewer than 20 neighbours: the figure moves by tenths of a millimetre with any
  // change to the solver's trajectory; 7.1 mm since the split children move down the split error's
  // gradient, `split_position_steps` = 3, against 6.7 mm without: bound 7.5 mm)
  EXPECT_LT(t.splitsMerges, 2.5);
  EXPECT_LT(t.shares, 30.0);
  EXPECT_LT(std::abs(t.above), 0.0075);
}

// The desktop's default tank (r = 5 mm, 30 fine radii deep against 19 in the coarse one) stands closer to
// uniform-high's surface, but its deep coarse water under a fine surface keeps more particles circulating
// between the layers: measured 12.8 splits and merges and 68 shares a step of 2,712 particles (0.47 % and
// 2.5 % of them, against 0.17 % and 1.4 % in the coarse tank), the surface 4.8 mm above uniform-high's
// settled start (4.0 mm above its bare-lattice start before session 16).
// Most merged particles were fine ones carried under the surface, most split parents coarser ones come up
// to it (a scratch driver following the particles' ids; docs/method.md, "The adaptive tank at rest").
TEST(AdaptivePhysicsTest, DefaultHandTankAtRestStandsNearUniformHighAndChurnsBoundedly) {
  // uniform-high's surface at 1.5 s: 0.1258 m from its settled start (0.1266 m from the bare lattice before
  // session 16; 23,426 particles)
  const RestingTank t = restingTank("hand_tank.json", 0.1258);
  EXPECT_LT(t.splitsMerges, 16.0);
  EXPECT_LT(t.shares, 85.0);
  EXPECT_LT(std::abs(t.above), 0.006);
  EXPECT_LT(double(t.particles), 0.15 * 23426.0);
}

TEST(AdaptivePhysicsTest, PropellerDrawsFineParticlesIntoItsVorticesUnlikeSurfaceOnly) {
  SceneDesc scene = fp::engine::loadScene(std::string(FP_SOURCE_DIR) + "/assets/scenes/propeller.json");
  // the propeller's region, below the band of the surface: there only vorticity and shear can refine
  auto nearPropeller = [](const Vec3& x) {
    return std::abs(x.x()) < 0.12f && Vec3(0, x.y() - 0.17f, x.z()).norm() < 0.08f;
  };
  double meanMass[2] = {0.0, 0.0};
  const AdaptivityMode modes[2] = {AdaptivityMode::Surface, AdaptivityMode::FluidPlaying};
  // One run is one sample of a chaotic flow: its figure moved from 0.88 to 0.97 of surface-only's with the
  // last bits of the build's rounding (FMA or not). Three runs a mode, perturbed through the seed of the
  // split orientations, and their mean.
  const std::uint64_t seeds[] = {1, 2, 3};
  for (int k = 0; k < 2; ++k) {
    for (std::uint64_t seed : seeds) {
      scene.mode = modes[k];
      scene.params.seed = seed;
      Simulation sim(scene);
      // the mean mass near the propeller, averaged over frames from 0.3 s to 0.8 s (one frame is too noisy:
      // the region holds about a hundred particles)
      int frames = 0;
      double next = 0.3;
      double run = 0.0;
      while (sim.time() < 0.8) {
        sim.step();
        if (sim.time() >= next) {
          const ParticleSet& p = sim.particles();
          run += meanMassRatio(sim, [&](std::size_t i) { return nearPropeller(p.x[i]); });
          ++frames;
          next += 0.05;
        }
      }
      std::printf("%s, seed %d: mean mass near the propeller %.2f m_fine\n", modeName(modes[k]), int(seed),
                  run / frames);
      meanMass[k] += run / frames / double(std::size(seeds));
    }
  }
  std::printf("mean over the seeds: surface %.2f, fluidplaying %.2f (%.3f)\n", meanMass[0], meanMass[1],
              meanMass[1] / meanMass[0]);
  EXPECT_GT(meanMass[0], 3.0);
  // measured (portable build, f0dbf99's initial coarsening): surface 24.5 / 24.6 / 24.1 m_fine, fluidplaying
  // 17.6 / 17.2 / 17.1, means 24.4 and 17.3 (0.71; before it 22.5 and 19.0, 0.85; one run of each gave 0.88
  // with FMA, 0.71 before the refinement was CFL-limited, which keeps the fastest water by the blades
  // coarser)
  EXPECT_LT(meanMass[1], 0.92 * meanMass[0]) << "surface " << meanMass[0] << ", fluidplaying " << meanMass[1];
}

TEST(AdaptivePhysicsTest, InitialCoarseningDoesNotTakeWallsForFreeSurfaces) {
  // Extents 11.98 and 9.98 spacings wide and water 12 spacings deep put the lattice's outer layers about 2 d
  // from the side walls and the floor, at the edge of the 4 r support, as in the hand tank at r = 5 mm: its
  // z walls and floor were taken for free surfaces, so every wall stayed lined with fine particles.
  const double r = 0.005;
  const double d = 2.0 * r;
  SceneDesc scene = tankScene(Vec3d(23.98 * r, 0.15, 19.98 * r), Vec3d(-23.98 * r, 0.0, -19.98 * r),
                              Vec3d(23.98 * r, 12.0 * d, 19.98 * r), r);
  scene.mode = AdaptivityMode::FluidPlaying;
  scene.params.initialRelaxation = 0;  // the coarsened lattice itself
  Simulation sim(scene);
  const ParticleSet& p = sim.particles();
  double mFine = p.m[0];
  double top = -1.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    mFine = std::min(mFine, double(p.m[i]));
    top = std::max(top, double(p.x[i].y()));
  }
  std::size_t fine = 0;
  std::size_t fineDeep = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (double(p.m[i]) > 1.5 * mFine)
      continue;
    ++fine;
    // deeper than the three top layers, which are fine or nearly so (R_phi < 0.5 within 4 r)
    if (double(p.x[i].y()) < top - 2.5 * d)
      ++fineDeep;
  }
  std::printf("coarsened lattice: %zu particles, %zu fine, %zu of them more than 2.5 d below the top\n",
              p.size(), fine, fineDeep);
  // measured: 1,002 particles, 564 fine, 195 of them deep (0.19), in the edges and corners where the block
  // grids of edges 3 and 2 do not line up; before the wider lattice supports 1,424, 1,086 and 555 (0.39)
  EXPECT_LT(fineDeep, p.size() / 4) << fine << " fine particles in " << p.size();
}

TEST(AdaptivePhysicsTest, DamBreakSmallLongRunBoundedAndConserving) {
  SceneDesc scene = tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0.0, -0.1), Vec3d(-0.05, 0.3, 0.1), 0.008);
  scene.mode = AdaptivityMode::FluidPlaying;
  SceneDesc uniform = scene;
  uniform.mode = AdaptivityMode::UniformHigh;
  const std::size_t nHigh = Simulation(uniform).particles().size();
  Simulation sim(scene);
  const double mass0 = sim.totalMass();
  const Vec3d p0 = sim.totalMomentum();
  std::size_t most = 0;
  while (sim.time() < 2.0) {
    ASSERT_NO_THROW(sim.step());
    most = std::max(most, sim.particles().size());
  }
  std::printf("adaptive dam break: most particles %zu, uniform-high %zu (%.3f)\n", most, nHigh,
              double(most) / double(nHigh));
  // measured: at most 756 particles against 2380 in uniform-high (0.32); bound 0.4 (it was 1.1)
  EXPECT_LE(double(most), 0.4 * double(nHigh));
  EXPECT_GT(sim.runStats().adaptivity.splits, 0u);
  EXPECT_GT(sim.runStats().adaptivity.merges, 0u);
  EXPECT_NEAR(sim.totalMass(), mass0, 1e-6 * mass0);
  const Vec3d gravityImpulse = mass0 * sim.time() * Vec3d(0, -9.81, 0);
  const Vec3d residual = sim.totalMomentum() - p0 - gravityImpulse - sim.boundaryImpulse();
  EXPECT_LT(residual.norm(), 1e-4 * gravityImpulse.norm()) << residual.transpose();
  for (const Vec3& x : sim.particles().x) {
    EXPECT_GE(x.y(), 0.0f);
    EXPECT_LE(std::abs(x.x()), 0.3f);
  }
}

TEST(AdaptivePhysicsTest, DamBreakSurgeFrontFollowsUniformHigh) {
  // The front of the collapsing column over the first 0.3 s, in fluidplaying and in uniform-high, both
  // settled before t = 0 (initial_relaxation); the tank is long enough that the front does not reach the far
  // wall. Two fronts (sim::surgeFront): the water's, beyond which lies 0.1 % of the mass (2.4 fine
  // particles' worth here), and the farthest particle's. The front is chaotic, and the exact lattice is a
  // special start: the adaptive modes' start coarsens it to 520 particles, where starts with particle radii
  // 1e-5 smaller (relative: the same lattice, 2,380 particles in uniform-high, moved by 0.03 %
  // of a spacing at most) coarsen to 548-554. So the figures are medians over five starts, the exact one and
  // radii 1, 2, 3 and 4 x 1e-5 smaller, each against the uniform-high run of its radius. Measured (session
  // 33) over the exact start and seven perturbed ones: the water's front leads uniform-high's by 4.4 % at
  // most on the exact start and by 6.5-7.8 % on the others, from 0.2 s on by 3.5 % and 5.7-7.1 %; the
  // farthest particle by 5.9 % and 6.3-7.4 %, from 0.2 s on by 1.2 % and 4.0-5.1 %. Issue 13's goal (within 5
  // %) holds on the exact start only; the bounds below keep what the perturbed starts show. (Session 30: the
  // merges make the lead, and with uniform-high started from the unsettled lattice, as before session 16, it
  // stood still for some 30 ms and fluidplaying led it by 8.1 %.)
  constexpr double kWaterBeyond = 0.001;
  constexpr int kStarts = 5;
  struct Fronts {
    std::vector<double> water, farthest;  // from the back wall, once every 25 ms
  };
  auto fronts = [&](AdaptivityMode mode, int start) {
    SceneDesc s = tankScene(Vec3d(0.6, 0.2, 0.1), Vec3d(-0.6, 0.0, -0.1), Vec3d(-0.35, 0.3, 0.1),
                            0.008 * (1.0 - 1e-5 * start));
    s.mode = mode;
    Simulation sim(s);
    Fronts out;
    for (int frame = 1; frame <= 12; ++frame) {
      while (sim.time() < 0.025 * frame)
        sim.step();
      out.water.push_back(surgeFront(sim.particles(), kWaterBeyond) + 0.6);
      out.farthest.push_back(surgeFront(sim.particles(), 0.0) + 0.6);
    }
    return out;
  };
  // the largest relative difference over the frames from `first` on
  auto lead = [](const std::vector<double>& a, const std::vector<double>& h, std::size_t first) {
    double worst = 0.0;
    for (std::size_t k = first; k < h.size(); ++k)
      worst = std::max(worst, std::abs(a[k] - h[k]) / h[k]);
    return worst;
  };
  std::vector<double> water, waterLate, farthest, farthestLate;
  for (int start = 0; start < kStarts; ++start) {
    const Fronts high = fronts(AdaptivityMode::UniformHigh, start);
    const Fronts adaptive = fronts(AdaptivityMode::FluidPlaying, start);
    if (start == 0) {
      for (std::size_t k = 0; k < high.water.size(); ++k)
        std::printf(
            "  t = %.3f s: water's front %.4f m against %.4f m, farthest particle %.4f m against %.4f m\n",
            0.025 * double(k + 1), adaptive.water[k], high.water[k], adaptive.farthest[k], high.farthest[k]);
    }
    water.push_back(lead(adaptive.water, high.water, 0));
    waterLate.push_back(lead(adaptive.water, high.water, 7));  // from 0.2 s on
    farthest.push_back(lead(adaptive.farthest, high.farthest, 0));
    farthestLate.push_back(lead(adaptive.farthest, high.farthest, 7));
    std::printf(
        "start %d: surge front, fluidplaying against uniform-high over 0.3 s: the water's (%.1f %% of the "
        "mass beyond) %.1f %% at most, %.1f %% from 0.2 s on; the farthest particle's %.1f %%, %.1f %% from "
        "0.2 s on\n",
        start, 100.0 * kWaterBeyond, 100.0 * water.back(), 100.0 * waterLate.back(), 100.0 * farthest.back(),
        100.0 * farthestLate.back());
    // the front has moved: the column collapsed
    EXPECT_GT(high.water.back(), 1.5 * high.water.front());
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf(
      "medians over %d starts: water's front %.1f %%, %.1f %% from 0.2 s on; farthest %.1f %%, %.1f %%\n",
      kStarts, 100.0 * median(water), 100.0 * median(waterLate), 100.0 * median(farthest),
      100.0 * median(farthestLate));
  // measured medians 6.5 %, 5.8 %, 6.3 % and 4.3 %
  EXPECT_LT(median(water), 0.08);
  EXPECT_LT(median(waterLate), 0.075);
  EXPECT_LT(median(farthest), 0.085);
  EXPECT_LT(median(farthestLate), 0.06);
}

TEST(AdaptivePhysicsTest, FluidBlocksKeepTheirInitialVelocityThroughTheSettlingInEveryMode) {
  // Two blocks thrown at each other. Every mode settles its start with the velocities held at zero
  // (initial_relaxation); the blocks' velocities must then be there at t = 0: before session 16 uniform-low
  // and the adaptive modes started them at rest.
  SceneDesc scene = tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.25, 0.0, -0.08), Vec3d(-0.1, 0.12, 0.08), 0.008);
  scene.fluid[0].velocity = Vec3d(0.4, 0.0, 0.0);
  scene.fluid.push_back(
      FluidBlock{Aabb(Vec3d(0.05, 0.0, -0.08), Vec3d(0.2, 0.12, 0.08)), Vec3d(-0.3, 0.1, 0.0)});
  std::vector<double> momentumX;
  for (AdaptivityMode mode : {AdaptivityMode::UniformHigh, AdaptivityMode::UniformLow,
                              AdaptivityMode::Surface, AdaptivityMode::FluidPlaying}) {
    SCOPED_TRACE(modeName(mode));
    scene.mode = mode;
    const Simulation sim(scene);
    const ParticleSet& p = sim.particles();
    double left = 0.0, right = 0.0;  // mass on each side of the gap between the blocks
    for (std::size_t i = 0; i < p.size(); ++i) {
      const bool inLeft = p.x[i].x() < -0.025f;
      const Vec3 expected = inLeft ? Vec3(0.4f, 0.0f, 0.0f) : Vec3(-0.3f, 0.1f, 0.0f);
      ASSERT_LT((p.v[i] - expected).norm(), 1e-6f) << "particle " << i << " at " << p.x[i].transpose();
      (inLeft ? left : right) += double(p.m[i]);
    }
    // the blocks are of equal volume: equal masses to the lattice's resolution
    EXPECT_NEAR(left / right, 1.0, 0.02);
    EXPECT_NEAR(sim.totalMomentum().x(), 0.4 * left - 0.3 * right, 1e-4 * (left + right));
    EXPECT_NEAR(sim.totalMomentum().y(), 0.1 * right, 1e-4 * (left + right));
    momentumX.push_back(sim.totalMomentum().x());
  }
  // the same water in every mode
  for (double px : momentumX)
    EXPECT_NEAR(px, momentumX.front(), 0.02 * std::abs(momentumX.front()) + 1e-3);
}

TEST(AdaptivePhysicsTest, TouchingFluidBlocksKeepEachParticlesOwnVelocityThroughTheSettling) {
  // Two blocks whose lattices meet one spacing apart (as the shear layer of PhysicsTest.Laminar...), sliding
  // past each other, no gravity: after the settling every particle of the uniform modes moves exactly as in
  // the unsettled build (same ids), whichever side of the face round-off put it.
  SceneDesc scene;
  scene.params.particleRadius = 0.008;
  scene.params.gravity = {0.0, 0.0, 0.0};
  scene.domain = Aabb(Vec3d(-0.2, -0.2, -0.2), Vec3d(0.2, 0.2, 0.2));
  scene.fluid.push_back(
      FluidBlock{Aabb(Vec3d(-0.08, -0.064, -0.048), Vec3d(0.08, 0.0, 0.048)), Vec3d(0.2, 0, 0)});
  scene.fluid.push_back(
      FluidBlock{Aabb(Vec3d(-0.08, -0.016, -0.048), Vec3d(0.08, 0.08, 0.048)), Vec3d(-0.2, 0, 0)});
  for (AdaptivityMode mode : {AdaptivityMode::UniformHigh, AdaptivityMode::UniformLow,
                              AdaptivityMode::Surface, AdaptivityMode::FluidPlaying}) {
    SCOPED_TRACE(modeName(mode));
    scene.mode = mode;
    SceneDesc bare = scene;
    bare.params.initialRelaxation = 0;
    const Simulation settled(scene), unsettled(bare);
    const bool uniform = mode == AdaptivityMode::UniformHigh || mode == AdaptivityMode::UniformLow;
    if (uniform) {
      std::vector<Vec3> byId;
      for (std::size_t i = 0; i < unsettled.particles().size(); ++i) {
        const std::uint32_t id = unsettled.particles().id[i];
        byId.resize(std::max<std::size_t>(byId.size(), std::size_t(id) + 1), Vec3::Zero());
        byId[id] = unsettled.particles().v[i];
      }
      ASSERT_EQ(settled.particles().size(), unsettled.particles().size());
      for (std::size_t i = 0; i < settled.particles().size(); ++i) {
        const std::uint32_t id = settled.particles().id[i];
        ASSERT_LT(id, byId.size());
        ASSERT_EQ(settled.particles().v[i], byId[id]) << "particle id " << id;
      }
    }
    // The adaptive modes merge and share mass across the face while they settle, and a particle then moves
    // at its own block's velocity with the mass it received from the other: measured 16-17 % of the start's
    // momentum in this small blob (every particle within a few supports of the face). A known limit
    // (docs/method.md); before session 16 they lost all of it.
    const double mass = settled.totalMass();
    EXPECT_NEAR(settled.totalMomentum().x(), unsettled.totalMomentum().x(),
                (uniform ? 1e-6 : 0.2) * std::abs(unsettled.totalMomentum().x()));
    // the blocks are not equal: the start has momentum, which a lost velocity would change
    EXPECT_GT(std::abs(unsettled.totalMomentum().x()), 0.05 * 0.2 * mass);
  }
}

TEST(AdaptivePhysicsTest, DroppingMergedParticlesInTheNextSortChangesNothingSmall) {
  // A step that split or merged sorts the kept particles by cell at its end, which drops the removed ones,
  // and the next search skips its sort (setPresortAfterAdaptation); compacting first, then sorting in the
  // next search, must give the same run to the bit, at 1 and 2 threads.
  struct Restore {
    ~Restore() { setPresortAfterAdaptation(true); }
  } restore;
  SceneDesc scene =
      tankScene(Vec3d(0.15, 0.15, 0.08), Vec3d(-0.15, 0.0, -0.08), Vec3d(0.0, 0.2, 0.08), 0.008);
  scene.mode = AdaptivityMode::FluidPlaying;
  for (int threads : {1, 2}) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    std::vector<ParticleSet> results;
    std::vector<std::uint64_t> steps;
    for (const bool presort : {true, false}) {
      setPresortAfterAdaptation(presort);
      Simulation sim(scene);
      while (sim.time() < 0.3)
        sim.step();
      EXPECT_GT(sim.runStats().adaptivity.merges, 20u);
      EXPECT_GT(sim.runStats().adaptivity.splits, 0u);
      results.push_back(sim.particles());
      steps.push_back(sim.stepCount());
    }
    EXPECT_EQ(steps[0], steps[1]) << threads << " threads";
    // (compared particle by particle in id order: when the last step split or merged, the presorted run is
    // already in cell order and the other one only compacted, until its next search sorts it)
    const auto byId = [](const ParticleSet& p) {
      std::vector<std::size_t> order(p.size());
      std::iota(order.begin(), order.end(), std::size_t(0));
      std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return p.id[i] < p.id[j]; });
      ParticleSet sorted;
      for (std::size_t i : order) {
        const std::size_t k = sorted.add(p.x[i], p.v[i], p.m[i], p.H[i], p.rho[i]);
        sorted.id[k] = p.id[i];
      }
      return sorted;
    };
    const ParticleSet a = byId(results[0]);
    const ParticleSet b = byId(results[1]);
    ASSERT_EQ(a.size(), b.size()) << threads << " threads";
    EXPECT_EQ(a.id, b.id) << threads << " threads";
    EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(Vec3)), 0) << threads << " threads";
    EXPECT_EQ(std::memcmp(a.v.data(), b.v.data(), a.size() * sizeof(Vec3)), 0) << threads << " threads";
    EXPECT_EQ(std::memcmp(a.m.data(), b.m.data(), a.size() * sizeof(Real)), 0) << threads << " threads";
    EXPECT_EQ(std::memcmp(a.H.data(), b.H.data(), a.size() * sizeof(Real)), 0) << threads << " threads";
    EXPECT_EQ(std::memcmp(a.rho.data(), b.rho.data(), a.size() * sizeof(Real)), 0) << threads << " threads";
  }
}

TEST(AdaptivePhysicsTest, AdaptiveRunsSmallAreDeterministicAcrossThreadCounts) {
  SceneDesc scene =
      tankScene(Vec3d(0.15, 0.15, 0.08), Vec3d(-0.15, 0.0, -0.08), Vec3d(0.0, 0.2, 0.08), 0.008);
  scene.mode = AdaptivityMode::FluidPlaying;
  std::vector<ParticleSet> results;
  for (int threads : {1, 2, 2}) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    Simulation sim(scene);
    while (sim.time() < 0.3)
      sim.step();
    EXPECT_GT(sim.runStats().adaptivity.splits + sim.runStats().adaptivity.merges, 0u);
    results.push_back(sim.particles());
  }
  for (std::size_t k = 1; k < results.size(); ++k) {
    const ParticleSet& a = results[0];
    const ParticleSet& b = results[k];
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(a.m.data(), b.m.data(), a.size() * sizeof(Real)), 0);
    EXPECT_EQ(a.id, b.id);
  }
}
