// The splash post-process (docs/method.md, Splash) on hand-built neighbourhoods: the formula, which particles
// spawn, counts, determinism across frames and threads, and a simulation that is bit-identical with splash on
// and off. Tests named *Small* also run under the sanitizers in CI.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <set>

#include "sim/kernels.h"
#include "sim/simulation.h"
#include "sim/splash.h"
#include "tests/scene_fixtures.h"

using namespace fp::sim;

namespace {

constexpr Real kR = 0.01f;         // particle radius [m]
constexpr Real kH = 4 * kR;        // support radius [m]
constexpr Real kSpacing = 2 * kR;  // lattice spacing [m]
constexpr Real kRho0 = 1000.0f;    // rest density [kg/m^3]
const Real kMass = kRho0 * kSpacing * kSpacing * kSpacing;
const Aabb kDomain(Vec3d(-1, -1, -1), Vec3d(1, 1, 1));

SimParams splashParams() {
  SimParams p;
  p.particleRadius = kR;
  p.splashEnabled = true;
  p.splashNeighbors = 20;
  p.splashCount = 4;
  p.splashAlphaMin = 0.5;
  p.splashAlphaMax = 3.0;
  p.splashNoise = 0.0;
  return p;
}

std::size_t addParticle(ParticleSet& p, const Vec3& x, const Vec3& v = Vec3::Zero()) {
  return p.add(x, v, kMass, kH, kRho0);
}

// an n x 1 x n patch of particles at height y, centred on x = z = 0
void addPatch(ParticleSet& p, int n, Real y) {
  const Real c = Real(n - 1) / 2;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < n; ++k)
      addParticle(p, Vec3((Real(i) - c) * kSpacing, y, (Real(k) - c) * kSpacing));
  }
}

// an n^3 lattice block with its lowest corner particle at `lo`
void addBlock(ParticleSet& p, const Vec3& lo, int n) {
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k)
        addParticle(p, lo + kSpacing * Vec3(Real(i), Real(j), Real(k)));
    }
  }
}

// the splash particles of source `i`
std::vector<Vec3> splashOf(const SplashParticles& s, std::size_t i) {
  std::vector<Vec3> out;
  for (std::size_t o = 0; o < s.size(); ++o) {
    if (s.source[o] == i)
      out.push_back(s.x[o]);
  }
  return out;
}

// fluid neighbours of particle i by brute force
std::uint32_t neighbourCount(const ParticleSet& p, std::size_t i) {
  std::uint32_t c = 0;
  for (std::size_t j = 0; j < p.size(); ++j)
    c += j != i && (p.x[i] - p.x[j]).norm() < pairSupport(p.H[i], p.H[j]);
  return c;
}

bool sameBytes(const SplashParticles& a, const SplashParticles& b) {
  return a.size() == b.size() && std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(Vec3)) == 0 &&
         std::memcmp(a.radius.data(), b.radius.data(), a.size() * sizeof(Real)) == 0 && a.source == b.source;
}

// N_splash for the messy scene: below the 17 neighbours of a flat face of the 2r lattice
constexpr int kMessyNeighbors = 12;

// a jittered lattice block with 60 flying droplets: many surface particles, some of them sparse
ParticleSet messyScene() {
  ParticleSet p;
  addBlock(p, Vec3(-0.2f, -0.2f, -0.2f), 16);
  std::uint64_t state = 7;
  auto next = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return Real(double(state >> 11) * 0x1.0p-53) - Real(0.5);
  };
  for (Vec3& x : p.x)
    x += Real(0.3) * kR * Vec3(next(), next(), next());
  for (int d = 0; d < 60; ++d)
    addParticle(p,
                Vec3(-0.25f + 0.05f * Real(d % 10), 0.2f + 0.01f * Real(d % 3), -0.2f + 0.08f * Real(d / 10)),
                Vec3(next(), 1.0f, next()));
  return p;
}

}  // namespace

TEST(SplashTest, FormulaOnAHandBuiltNeighbourhoodSmall) {
  // a particle with two neighbours at known offsets: xhat_i = V (2r W(2r, H), 3r W(3r, H), 0) since
  // x_ij points away from each neighbour
  ParticleSet p;
  const std::size_t i = addParticle(p, Vec3(0.1f, 0.2f, 0.3f));
  addParticle(p, Vec3(0.1f - 2 * kR, 0.2f, 0.3f));
  addParticle(p, Vec3(0.1f, 0.2f - 3 * kR, 0.3f));
  const Real v = kMass / kRho0;
  const Vec3 xhat(2 * kR * v * CubicSpline::w(2 * kR, kH), 3 * kR * v * CubicSpline::w(3 * kR, kH), 0);
  // W(2r, 4r) / W(3r, 4r) = 0.25 / 0.03125 = 8, so the direction is (0.5, 0.09375) normalised
  const Vec3 expected = Vec3(0.5f, 0.09375f, 0.0f).normalized();
  EXPECT_NEAR(xhat.normalized().x(), expected.x(), 1e-6);
  EXPECT_NEAR(xhat.normalized().y(), expected.y(), 1e-6);

  SimParams params = splashParams();
  params.splashAlphaMin = params.splashAlphaMax = 2.0;  // alpha = 2 r exactly
  SplashGenerator gen;
  const SplashParticles& s = gen.generate(p, BoundarySet{}, params, kDomain, 0);
  const std::vector<Vec3> mine = splashOf(s, i);
  ASSERT_EQ(mine.size(), 4u);
  for (const Vec3& x : mine) {
    const Vec3 want = p.x[i] + 2 * kR * expected;
    EXPECT_NEAR(x.x(), want.x(), 1e-6);
    EXPECT_NEAR(x.y(), want.y(), 1e-6);
    EXPECT_NEAR(x.z(), want.z(), 1e-6);
  }
  for (std::size_t o = 0; o < s.size(); ++o)
    EXPECT_FLOAT_EQ(s.radius[o], kSplashRadiusFraction * kR);
}

TEST(SplashTest, ParticleOnTopOfAPatchSpraysUpwardsWithinTheBoundsSmall) {
  ParticleSet p;
  addPatch(p, 7, 0.0f);
  const std::size_t top = addParticle(p, Vec3(0, kSpacing, 0));
  ASSERT_EQ(neighbourCount(p, top), 9u);  // the 3 x 3 below it

  // no noise: exactly along xhat = +y, at distances in [alpha_min, alpha_max] r
  SimParams params = splashParams();
  SplashGenerator gen;
  std::vector<Vec3> mine = splashOf(gen.generate(p, BoundarySet{}, params, kDomain, 3), top);
  ASSERT_EQ(mine.size(), 4u);
  for (const Vec3& x : mine) {
    const Vec3 d = x - p.x[top];
    EXPECT_GE(d.norm(), Real(params.splashAlphaMin) * kR * 0.9999f);
    EXPECT_LE(d.norm(), Real(params.splashAlphaMax) * kR * 1.0001f);
    EXPECT_NEAR(d.normalized().y(), 1.0, 1e-5);
  }

  // with noise n_r_max < 1 the direction stays within asin(n_r_max) of xhat, the distance in the bounds
  params.splashNoise = 0.5;
  params.splashCount = 32;
  mine = splashOf(gen.generate(p, BoundarySet{}, params, kDomain, 3), top);
  ASSERT_EQ(mine.size(), 32u);
  Real minCos = 1;
  for (const Vec3& x : mine) {
    const Vec3 d = x - p.x[top];
    EXPECT_GE(d.norm(), Real(params.splashAlphaMin) * kR * 0.9999f);
    EXPECT_LE(d.norm(), Real(params.splashAlphaMax) * kR * 1.0001f);
    EXPECT_GT(d.y(), 0.0f);  // the outward side
    minCos = std::min(minCos, d.normalized().y());
  }
  EXPECT_GE(minCos, std::sqrt(1.0f - 0.25f) - 1e-5f);
  EXPECT_LT(minCos, 0.999f);  // the noise does turn some of them
}

TEST(SplashTest, OnlySparseSurfaceParticlesSpawnSmall) {
  ParticleSet p;
  addBlock(p, Vec3(-0.08f, -0.08f, -0.08f), 9);
  const Vec3 centre = Vec3(-0.08f, -0.08f, -0.08f) + Vec3::Constant(4 * kSpacing);
  std::size_t interior = 0, topFace = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if ((p.x[i] - centre).norm() < 1e-5f)
      interior = i;
    if ((p.x[i] - (centre + Vec3(0, 4 * kSpacing, 0))).norm() < 1e-5f)
      topFace = i;
  }
  ASSERT_EQ(neighbourCount(p, interior), 26u);
  ASSERT_EQ(neighbourCount(p, topFace), 17u);  // a flat face of the 2r lattice: 8 beside, 9 below
  // a lone droplet, listed in the middle of the set, and a sparse cluster of four
  const std::size_t lone = addParticle(p, Vec3(0.5f, 0.5f, 0.5f), Vec3(0, 2, 0));
  addBlock(p, Vec3(-0.5f, 0.4f, -0.5f), 1);
  const std::size_t sparse = addParticle(p, Vec3(-0.5f + kSpacing, 0.4f, -0.5f));
  addParticle(p, Vec3(-0.5f, 0.4f + kSpacing, -0.5f));
  addParticle(p, Vec3(-0.5f, 0.4f, -0.5f + kSpacing));
  addBlock(p, Vec3(0.3f, -0.3f, 0.3f), 2);

  SimParams params = splashParams();
  params.splashNeighbors = 12;  // below a flat face's 17
  SplashGenerator gen;
  const SplashParticles& s = gen.generate(p, BoundarySet{}, params, kDomain, 0);
  EXPECT_TRUE(splashOf(s, interior).empty());
  EXPECT_TRUE(splashOf(s, topFace).empty());
  EXPECT_EQ(splashOf(s, lone).size(), 4u);
  EXPECT_EQ(splashOf(s, sparse).size(), 4u);
  // the lone droplet has no neighbours: it sprays along its velocity
  for (const Vec3& x : splashOf(s, lone))
    EXPECT_NEAR((x - p.x[lone]).normalized().y(), 1.0, 1e-6);
  // every source has fewer than N_splash neighbours
  for (std::uint32_t src : std::set<std::uint32_t>(s.source.begin(), s.source.end()))
    EXPECT_LT(neighbourCount(p, src), 12u) << src;

  // the flat-face particle spawns once N_splash exceeds its neighbour count; the interior one never does
  params.splashNeighbors = 18;
  const SplashParticles& s2 = gen.generate(p, BoundarySet{}, params, kDomain, 0);
  EXPECT_EQ(splashOf(s2, topFace).size(), 4u);
  params.splashNeighbors = 200;
  EXPECT_TRUE(splashOf(gen.generate(p, BoundarySet{}, params, kDomain, 0), interior).empty());
}

TEST(SplashTest, ALoneDropletAtRestStillSpraysAndADropletOnTheFloorSpraysUpSmall) {
  // a tank of boundary particles; one droplet resting near its floor, one at rest in mid air
  ColliderState tank;
  tank.desc.shape = ShapeType::Box;
  tank.desc.container = true;
  tank.desc.halfExtents = Vec3d(0.1, 0.1, 0.1);
  tank.desc.position = tank.position = Vec3d(0, 0.1, 0);
  BoundarySet boundary;
  boundary.build({tank}, kR);
  ParticleSet p;
  const std::size_t onFloor = addParticle(p, Vec3(0.0f, kR, 0.0f));
  const std::size_t still = addParticle(p, Vec3(0.05f, 0.1f, 0.0f));
  SimParams params = splashParams();
  SplashGenerator gen;
  const SplashParticles& s = gen.generate(p, boundary, params, kDomain, 1);
  const std::vector<Vec3> floorSplash = splashOf(s, onFloor);
  ASSERT_EQ(floorSplash.size(), 4u);
  for (const Vec3& x : floorSplash)
    EXPECT_NEAR((x - p.x[onFloor]).normalized().y(), 1.0, 1e-4);
  // no neighbours, no velocity and no noise: random unit directions, still within the distance bounds
  const std::vector<Vec3> stillSplash = splashOf(s, still);
  ASSERT_EQ(stillSplash.size(), 4u);
  for (const Vec3& x : stillSplash) {
    EXPECT_TRUE(x.allFinite());
    EXPECT_GE((x - p.x[still]).norm(), Real(params.splashAlphaMin) * kR * 0.9999f);
    EXPECT_LE((x - p.x[still]).norm(), Real(params.splashAlphaMax) * kR * 1.0001f);
  }
  EXPECT_GT((stillSplash[0] - stillSplash[1]).norm(), 1e-4f);
}

TEST(SplashTest, KeepsItsSortedWallsOnlyWhileTheStaticBoundaryIsTheSameSmall) {
  // The generator sorts the static boundary once and keeps it while the boundary's staticVersion() holds: a
  // different tank, and the same tank reordered, each give what a fresh generator gives, the droplet on the
  // floor spraying up from the floor it rests on.
  auto tankAt = [](double floorY) {
    ColliderState tank;
    tank.desc.shape = ShapeType::Box;
    tank.desc.container = true;
    tank.desc.halfExtents = Vec3d(0.1, 0.1, 0.1);
    tank.desc.position = tank.position = Vec3d(0, floorY + 0.1, 0);
    BoundarySet boundary;
    boundary.build({tank}, kR);
    return boundary;
  };
  const BoundarySet first = tankAt(0.0);
  BoundarySet second = tankAt(-0.04);
  EXPECT_NE(first.staticVersion(), second.staticVersion());
  ParticleSet p;
  const std::size_t onFloor = addParticle(p, Vec3(0.0f, Real(-0.04) + kR, 0.0f));
  const SimParams params = splashParams();
  SplashGenerator gen;
  gen.generate(p, first, params, kDomain, 1);
  const SplashParticles onSecond = gen.generate(p, second, params, kDomain, 1);
  SplashGenerator fresh;
  EXPECT_TRUE(sameBytes(onSecond, fresh.generate(p, second, params, kDomain, 1)));
  const std::vector<Vec3> up = splashOf(onSecond, onFloor);
  ASSERT_EQ(up.size(), 4u);
  for (const Vec3& x : up)
    EXPECT_NEAR((x - p.x[onFloor]).normalized().y(), 1.0, 1e-4);
  // reordered: a new version, and the cached order is not used for it
  const std::uint64_t version = second.staticVersion();
  std::vector<std::uint32_t> reversed(second.staticCount());
  for (std::size_t k = 0; k < reversed.size(); ++k)
    reversed[k] = std::uint32_t(reversed.size() - 1 - k);
  second.permute(0, reversed);
  EXPECT_NE(second.staticVersion(), version);
  const SplashParticles reorderedOut = gen.generate(p, second, params, kDomain, 1);
  SplashGenerator fresh2;
  EXPECT_TRUE(sameBytes(reorderedOut, fresh2.generate(p, second, params, kDomain, 1)));
  for (const Vec3& x : splashOf(reorderedOut, onFloor))
    EXPECT_NEAR((x - p.x[onFloor]).normalized().y(), 1.0, 1e-4);
}

TEST(SplashTest, OnTheSimulationsCurrentListsItSpraysWhatItsOwnSearchGivesSmall) {
  // Between the app loop's steps the simulation holds the lists of its current state
  // (Simulation::prepareNeighbors) and the generator uses them instead of searching: the same spawning
  // particles and splash particles, up to the order of the sums.
  SceneDesc scene = fp::test::withPaddle(
      fp::test::tankScene(Vec3d(0.2, 0.12, 0.08), Vec3d(-0.2, 0.0, -0.08), Vec3d(0.2, 0.12, 0.08), 0.01),
      0.03, Vec3d(-0.1, 0.09, 0.0), Vec3d(0.8, 0.0, 0.0));
  scene.mode = AdaptivityMode::FluidPlaying;
  scene.params.massRatio = 8.0;
  scene.params.splashEnabled = true;
  scene.params.splashCount = 4;
  Simulation simulation(scene);
  for (int k = 0; k < 20; ++k)
    simulation.step();
  ASSERT_FALSE(simulation.neighborsCurrent());
  SplashGenerator own;
  const SplashParticles searched = own.generate(simulation.particles(), simulation.boundary(),
                                                simulation.params(), simulation.scene().domain, 7);
  simulation.prepareNeighbors();
  // the search reordered the particles: compare by particle id
  SplashGenerator shared;
  const SplashParticles& onLists = shared.generate(simulation, 7);
  SplashGenerator ownAfter;
  const SplashParticles& reference = ownAfter.generate(simulation.particles(), simulation.boundary(),
                                                       simulation.params(), simulation.scene().domain, 7);
  ASSERT_GT(reference.size(), 20u);
  EXPECT_EQ(searched.size(), reference.size());
  ASSERT_EQ(onLists.size(), reference.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < reference.size(); ++k) {
    ASSERT_EQ(onLists.source[k], reference.source[k]);
    worst = std::max(worst, double((onLists.x[k] - reference.x[k]).norm()));
    EXPECT_EQ(onLists.radius[k], reference.radius[k]);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(SplashTest, CountsScaleWithNSplashAndSwitchOffSmall) {
  const ParticleSet p = messyScene();
  const ParticleSet before = p;
  SimParams params = splashParams();
  params.splashNoise = 0.5;
  params.splashNeighbors = kMessyNeighbors;
  SplashGenerator gen;
  std::vector<std::uint32_t> spawners;
  for (int count : {1, 2, 4, 7}) {
    params.splashCount = count;
    const SplashParticles& s = gen.generate(p, BoundarySet{}, params, kDomain, 5);
    ASSERT_EQ(s.radius.size(), s.size());
    ASSERT_EQ(s.source.size(), s.size());
    std::vector<std::uint32_t> sources;
    for (std::size_t o = 0; o < s.size(); o += std::size_t(count)) {
      for (int k = 0; k < count; ++k) {
        ASSERT_EQ(s.source[o + std::size_t(k)], s.source[o]);  // exactly n_splash per source, together
      }
      if (!sources.empty()) {
        EXPECT_GT(s.source[o], sources.back());  // ordered by source index
      }
      sources.push_back(s.source[o]);
    }
    EXPECT_EQ(s.size(), sources.size() * std::size_t(count));
    if (spawners.empty())
      spawners = sources;
    EXPECT_EQ(sources, spawners);  // the same particles spawn whatever n_splash
  }
  EXPECT_GT(spawners.size(), 60u);           // the droplets and the block's corners at least
  EXPECT_LT(spawners.size(), p.size() / 4);  // ... but not the whole block
  params.splashCount = 0;
  EXPECT_EQ(gen.generate(p, BoundarySet{}, params, kDomain, 5).size(), 0u);
  params.splashCount = 4;
  params.splashEnabled = false;
  EXPECT_EQ(gen.generate(p, BoundarySet{}, params, kDomain, 5).size(), 0u);
  EXPECT_EQ(gen.splash().size(), 0u);
  // the caller's particles are untouched (surface flags included)
  EXPECT_EQ(std::memcmp(p.x.data(), before.x.data(), p.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(p.flags, before.flags);
}

TEST(SplashTest, DeterministicPerFrameAndThreadCountSmall) {
  const ParticleSet p = messyScene();
  SimParams params = splashParams();
  params.splashNoise = 0.5;
  params.splashNeighbors = kMessyNeighbors;
  SplashGenerator a, b;
  const SplashParticles first = a.generate(p, BoundarySet{}, params, kDomain, 11);
  ASSERT_GT(first.size(), 0u);
  EXPECT_TRUE(sameBytes(first, a.generate(p, BoundarySet{}, params, kDomain, 11)));
  EXPECT_TRUE(sameBytes(first, b.generate(p, BoundarySet{}, params, kDomain, 11)));
  // another frame: the same sources, other offsets
  const SplashParticles& other = a.generate(p, BoundarySet{}, params, kDomain, 12);
  ASSERT_EQ(other.size(), first.size());
  EXPECT_EQ(other.source, first.source);
  std::size_t moved = 0;
  for (std::size_t o = 0; o < first.size(); ++o)
    moved += (other.x[o] - first.x[o]).norm() > 1e-6f;
  EXPECT_GT(moved, first.size() * 9 / 10);
  // another seed: other offsets too
  params.seed = 2;
  EXPECT_FALSE(sameBytes(first, a.generate(p, BoundarySet{}, params, kDomain, 11)));
  params.seed = 1;
  // one thread and two threads
  SplashParticles one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    SplashGenerator g;
    one = g.generate(p, BoundarySet{}, params, kDomain, 11);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    SplashGenerator g;
    two = g.generate(p, BoundarySet{}, params, kDomain, 11);
  }
  EXPECT_TRUE(sameBytes(one, first));
  EXPECT_TRUE(sameBytes(one, two));
  // the order of the particles in the set does not change the spray of a particle id
  ParticleSet reversed;
  for (std::size_t i = p.size(); i-- > 0;)
    addParticle(reversed, p.x[i], p.v[i]);
  for (std::size_t i = 0; i < p.size(); ++i)
    reversed.id[i] = p.id[p.size() - 1 - i];
  const SplashParticles& r = a.generate(reversed, BoundarySet{}, params, kDomain, 11);
  ASSERT_EQ(r.size(), first.size());
  const std::size_t count = std::size_t(params.splashCount);
  for (std::size_t o = 0; o < r.size(); o += count) {
    const std::size_t mirror = first.size() - count - o;  // sources come in reverse order
    ASSERT_EQ(r.source[o], p.size() - 1 - first.source[mirror]);
    for (std::size_t k = 0; k < count; ++k)
      EXPECT_LT((r.x[o + k] - first.x[mirror + k]).norm(), 1e-6f);
  }
}

TEST(SplashTest, SplashIsAFunctionOfTheStateAndTheFrameSmall) {
  // The splash is render-only: it must depend on the simulation's state and the frame number alone, not on
  // the generator's history.
  // (Bit-identity of the simulation with splash on and off holds by construction: the generator takes const
  // references.) A dam break of about 2k particles in a tank, 0.3 s, splash generated every 1/60 s.
  SceneDesc scene;
  scene.name = "splash dam break";
  scene.params.particleRadius = 0.01;
  ColliderDesc tank;
  tank.name = "tank";
  tank.shape = ShapeType::Box;
  tank.container = true;
  tank.halfExtents = Vec3d(0.3, 0.2, 0.12);
  tank.position = Vec3d(0, 0.2, 0);
  scene.colliders.push_back(tank);
  scene.fluid.push_back(FluidBlock{Aabb(Vec3d(-0.3, 0.0, -0.12), Vec3d(-0.04, 0.38, 0.12)), Vec3d::Zero()});
  scene.domain = Aabb(Vec3d(-0.35, -0.05, -0.17), Vec3d(0.35, 0.45, 0.17));

  Simulation sprayed(scene);
  ASSERT_GT(sprayed.particles().size(), 1500u);
  SplashGenerator gen;
  std::uint64_t frame = 0;
  std::size_t maxSplash = 0;
  double nextFrame = 0.0;
  while (sprayed.time() < 0.3) {
    if (sprayed.time() >= nextFrame) {
      maxSplash = std::max(maxSplash, gen.generate(sprayed, frame++).size());
      nextFrame += 1.0 / 60.0;
    }
    sprayed.step();
  }
  EXPECT_GE(frame, 17u);
  EXPECT_GT(maxSplash, 0u);
  // splash particles equal bit for bit, their sources named by stable id
  auto sourceIds = [](const SplashParticles& sp, const Simulation& sim) {
    std::vector<std::uint32_t> ids;
    for (std::uint32_t i : sp.source)
      ids.push_back(sim.particles().id[i]);
    return ids;
  };
  auto same = [&](const SplashParticles& a, const Simulation& simA, const SplashParticles& b,
                  const Simulation& simB) {
    return a.size() == b.size() && sourceIds(a, simA) == sourceIds(b, simB) &&
           std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(Vec3)) == 0 &&
           std::memcmp(a.radius.data(), b.radius.data(), a.size() * sizeof(Real)) == 0;
  };
  const SplashParticles used = gen.generate(sprayed, frame);
  ASSERT_GT(used.size(), 0u);
  SplashGenerator fresh;
  EXPECT_TRUE(same(used, sprayed, fresh.generate(sprayed, frame), sprayed))
      << "the generator's history changed the splash";
  EXPECT_FALSE(same(used, sprayed, fresh.generate(sprayed, frame + 1), sprayed))
      << "the frame number does not vary the splash";
}
