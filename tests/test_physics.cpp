// Physics of the SPH core on small scenes: hydrostatic rest, a dam break, conservation, determinism and the
// reporting of instabilities. Tests named *Small* also run under the sanitizers in CI.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "sim/ply_writer.h"
#include "sim/signed_distance.h"
#include "sim/simulation.h"
#include "tests/scene_fixtures.h"
#include "tests/temp_path.h"

using namespace fp::sim;
using fp::test::tankScene;

namespace {

SceneDesc smallDamBreak() {
  return tankScene(Vec3d(0.3, 0.2, 0.1), Vec3d(-0.3, 0.0, -0.1), Vec3d(-0.1, 0.3, 0.1), 0.008);
}

bool bitIdentical(const ParticleSet& a, const ParticleSet& b) {
  return a.size() == b.size() && std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(Vec3)) == 0 &&
         std::memcmp(a.v.data(), b.v.data(), a.size() * sizeof(Vec3)) == 0 && a.id == b.id;
}

}  // namespace

TEST(PhysicsTest, TankAtRestSettlesHydrostatically) {
  const double depth = 0.2;
  // r = 0.1 / 20.4 puts the lattice 2.4 r from every wall, near the rest distance of Akinci boundaries
  SceneDesc scene =
      tankScene(Vec3d(0.1, 0.15, 0.1), Vec3d(-0.1, 0, -0.1), Vec3d(0.1, depth, 0.1), 0.1 / 20.4);
  Simulation sim(scene);
  const std::size_t n = sim.particles().size();
  ASSERT_GT(n, 3000u);
  while (sim.time() < 1.5)
    sim.step();
  const double rho0 = scene.params.restDensity;
  const double g = 9.81;
  Vec3d comBefore = Vec3d::Zero();
  for (const Vec3& x : sim.particles().x)
    comBefore += x.cast<double>() / double(n);
  const Vec3d impulseBefore = sim.boundaryImpulse();
  const double t0 = sim.time();
  // bottom pressure p = k rho^2 / rho0 (both solves) near the floor, away from the side walls, against rho g
  // h; the free surface lies a particle radius above the top layer. The layer touching the floor is left out:
  // with Akinci's mirrored pressure the wall pushes with the particle's own stiffness only, so that layer
  // carries ~1.4x. One step's ratio scatters by 6 % (standard deviation over the steps from 1 s to 2 s, mean
  // 0.98): it is averaged over the steps of the last 0.5 s.
  const double floorLayerTop = 3.5 * scene.params.particleRadius;
  auto bottomPressureRatio = [&](int& count) {
    const ParticleSet& q = sim.particles();
    double top = 0.0;
    for (const Vec3& x : q.x)
      top = std::max(top, double(x.y()));
    const double surface = top + scene.params.particleRadius;
    double pSum = 0.0, expectSum = 0.0;
    count = 0;
    for (std::size_t i = 0; i < q.size(); ++i) {
      const Vec3& x = q.x[i];
      if (x.y() > floorLayerTop && x.y() < 0.045 && std::abs(x.x()) < 0.06 && std::abs(x.z()) < 0.06) {
        pSum += sim.pressure(i);
        expectSum += rho0 * g * (surface - x.y());
        ++count;
      }
    }
    return count > 0 ? pSum / expectSum : 0.0;
  };
  double ratioSum = 0.0;
  int ratioSteps = 0;
  int count = 0;
  while (sim.time() < 2.0) {
    sim.step();
    const double ratio = bottomPressureRatio(count);
    ASSERT_GT(count, 10);
    ratioSum += ratio;
    ++ratioSteps;
  }
  const double pressureRatio = ratioSum / ratioSteps;
  const ParticleSet& p = sim.particles();

  // density error bound
  EXPECT_LT(sim.lastStep().densityError, 0.005);
  // no drift: the water is still and its centre of mass stays put
  double maxSpeed = 0.0, meanSpeed = 0.0;
  Vec3d comAfter = Vec3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    maxSpeed = std::max(maxSpeed, double(p.v[i].norm()));
    meanSpeed += double(p.v[i].norm()) / double(n);
    comAfter += p.x[i].cast<double>() / double(n);
  }
  std::printf(
      "tank at rest after 2 s: mean speed %.4f m/s, max %.4f m/s, centre of mass moved %.3g m; bottom "
      "pressure "
      "%.4f of hydrostatic (mean over the last 0.5 s)\n",
      meanSpeed, maxSpeed, (comAfter - comBefore).norm(), pressureRatio);
  // residual jitter of a still tank with weak XSPH damping: measured 2.75 cm/s mean and 16.1 cm/s at most
  // after 2 s from the bare lattice, 2.57 and 14.1 cm/s from the settled start (session 16); bounds 1.25x the
  // first
  EXPECT_LT(meanSpeed, 0.035);
  EXPECT_LT(maxSpeed, 0.2);
  EXPECT_LT((comAfter - comBefore).norm(), 1e-3);
  // the walls carry the weight: boundary impulse per second equals -M g within 1%
  const Vec3d force = (sim.boundaryImpulse() - impulseBefore) / (sim.time() - t0);
  EXPECT_NEAR(force.y(), sim.totalMass() * g, 0.01 * sim.totalMass() * g);

  EXPECT_NEAR(pressureRatio, 1.0, 0.05) << "mean speed " << meanSpeed << " max " << maxSpeed
                                        << " bottom pressure over hydrostatic, mean over the last 0.5 s";
}

TEST(PhysicsTest, DamBreakSmallStaysInsideAndConserves) {
  SceneDesc scene = smallDamBreak();
  Simulation sim(scene);
  const std::size_t n = sim.particles().size();
  ASSERT_GT(n, 1500u);
  const double mass0 = sim.totalMass();
  const Vec3d p0 = sim.totalMomentum();
  // mechanical energy, kinetic plus potential above the floor
  auto energy = [&] {
    const ParticleSet& p = sim.particles();
    double e = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      e += double(p.m[i]) * (0.5 * double(p.v[i].squaredNorm()) + 9.81 * double(p.x[i].y()));
    return e;
  };
  const double e0 = energy();
  double maxSpeed = 0.0;
  double eMax = e0;
  double ePrev = e0;
  double gained = 0.0, worstGain = 0.0;
  double maxSpeedTime = 0.0;
  while (sim.time() < 1.5) {
    ASSERT_NO_THROW(sim.step());
    double stepFastest = 0.0;
    for (const Vec3& v : sim.particles().v)
      stepFastest = std::max(stepFastest, double(v.norm()));
    // the step's figure is its fastest particle, and the run's the largest over steps, with its time
    ASSERT_EQ(sim.lastStep().maxSpeed, stepFastest) << "step " << sim.stepCount();
    if (stepFastest > maxSpeed)
      maxSpeedTime = sim.time();
    maxSpeed = std::max(maxSpeed, stepFastest);
    const double e = energy();
    eMax = std::max(eMax, e);
    gained += std::max(0.0, e - ePrev);
    worstGain = std::max(worstGain, e - ePrev);
    ePrev = e;
  }
  // The water only loses mechanical energy (viscosity, the walls, the pressure solves): measured, the total
  // never rose in any step (0 J gained over the run) and ended at 0.36 of its start (4.33 of 11.87 J; at rest
  // it would be a third). Energy fed in by a wrong sign (anti-viscosity: 0.028 J gained over the run) fails;
  // the bound is 1e-5 of the start (1.2e-4 J).
  std::printf(
      "dam break energy: start %.4f J, most %.4f J, end %.4f J, gained over steps %.3g J (worst step "
      "%.3g J)\n",
      e0, eMax, energy(), gained, worstGain);
  EXPECT_LE(gained, 1e-5 * e0);
  EXPECT_LT(energy(), 0.5 * e0);
  EXPECT_GT(maxSpeed, 1.5);  // the water really fell and ran
  EXPECT_EQ(sim.runStats().maxSpeed, maxSpeed);
  EXPECT_EQ(sim.runStats().maxSpeedTime, maxSpeedTime);
  // no escaped particle: all inside the container (boundary particles sit on its faces)
  for (const Vec3& x : sim.particles().x) {
    ASSERT_TRUE(x.allFinite());
    EXPECT_GE(x.x(), -0.3f);
    EXPECT_LE(x.x(), 0.3f);
    EXPECT_GE(x.y(), 0.0f);
    EXPECT_GE(x.z(), -0.1f);
    EXPECT_LE(x.z(), 0.1f);
  }
  // momentum changes only by gravity and boundary forces
  const Vec3d gravityImpulse = mass0 * sim.time() * Vec3d(0, -9.81, 0);
  const Vec3d residual = sim.totalMomentum() - p0 - gravityImpulse - sim.boundaryImpulse();
  EXPECT_LT(residual.norm(), 1e-4 * gravityImpulse.norm()) << residual.transpose();
}

TEST(PhysicsTest, CollidingBlocksSmallConserveMomentumWithoutWalls) {
  SceneDesc s;
  s.params.particleRadius = 0.01;
  s.params.gravity = {0, 0, 0};
  s.params.surfaceTension = 0.5;
  s.domain = Aabb(Vec3d(-1, -1, -1), Vec3d(1, 1, 1));
  s.fluid.push_back(
      FluidBlock{Aabb(Vec3d(-0.25, -0.08, -0.08), Vec3d(-0.05, 0.08, 0.08)), Vec3d(1.0, 0.1, 0)});
  s.fluid.push_back(FluidBlock{Aabb(Vec3d(0.0, -0.1, -0.06), Vec3d(0.16, 0.06, 0.1)), Vec3d(-0.8, 0, 0.2)});
  Simulation sim(s);
  const ParticleSet& p = sim.particles();
  // the first block's particles by id (ids are the creation order, the first block first)
  std::vector<std::uint8_t> inFirst(p.size(), 0);
  for (std::size_t i = 0; i < p.size(); ++i)
    inFirst[p.id[i]] = p.x[i].x() < -0.025f;
  auto firstMomentum = [&] {
    Vec3d m = Vec3d::Zero();
    for (std::size_t i = 0; i < p.size(); ++i)
      if (inFirst[p.id[i]])
        m += double(p.m[i]) * p.v[i].cast<double>();
    return m;
  };
  auto centreOfMass = [&] {
    Vec3d c = Vec3d::Zero();
    for (std::size_t i = 0; i < p.size(); ++i)
      c += double(p.m[i]) * p.x[i].cast<double>();
    return Vec3d(c / sim.totalMass());
  };
  const Vec3d p0 = sim.totalMomentum();
  const Vec3d first0 = firstMomentum();
  const Vec3d com0 = centreOfMass();
  const double scale = sim.totalMass() * 1.0;
  while (sim.time() < 0.3)
    sim.step();
  EXPECT_LT((sim.totalMomentum() - p0).norm(), 1e-5 * scale) << (sim.totalMomentum() - p0).transpose();
  // The blocks did collide and push each other: the first block has given up most of its x-momentum
  // (measured: 3.53 -> 1.25 kg m/s from the bare lattice, 3.53 -> 1.40 settled), which a pressure solve that
  // never acts (the blocks passing through each other) would not do. (The density solve needs only its
  // minimum of 2 iterations a step here.)
  const Vec3d first = firstMomentum();
  EXPECT_LT(first.x(), 0.5 * first0.x());
  std::printf(
      "colliding blocks: first block's x-momentum %.4f -> %.4f kg m/s; density iterations %llu over %llu "
      "steps; centre of mass off its uniform motion by %.3g m; boundary impulse %.3g\n",
      first0.x(), first.x(), (unsigned long long)sim.runStats().densityIterations,
      (unsigned long long)sim.runStats().steps,
      (centreOfMass() - com0 - p0 / sim.totalMass() * sim.time()).norm(), sim.boundaryImpulse().norm());
  // with no walls and no gravity the centre of mass moves uniformly with the total momentum (measured 2e-9 m
  // off; a particle whose position is not advanced with its velocity moves it by ~1e-5 m)
  EXPECT_LT((centreOfMass() - com0 - p0 / sim.totalMass() * sim.time()).norm(), 1e-7);
}

TEST(PhysicsTest, RunsAreBitIdenticalSmall) {
  SceneDesc scene = smallDamBreak();
  auto run = [&](int threads) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    Simulation sim(scene);
    for (int k = 0; k < 120; ++k)
      sim.step();
    return sim.particles();
  };
  const ParticleSet a = run(1);
  const ParticleSet b = run(1);
  EXPECT_TRUE(bitIdentical(a, b));
  // the method is deterministic across thread counts too (fixed-grain reductions, ordered lists)
  const ParticleSet c = run(2);
  EXPECT_TRUE(bitIdentical(a, c));
}

TEST(PhysicsTest, SpinningPaddleSmallStirsTheWater) {
  SceneDesc scene = tankScene(Vec3d(0.15, 0.1, 0.15), Vec3d(-0.15, 0, -0.15), Vec3d(0.15, 0.1, 0.15), 0.008);
  ColliderDesc paddle;
  paddle.name = "paddle";
  paddle.shape = ShapeType::Box;
  paddle.halfExtents = Vec3d(0.08, 0.04, 0.01);
  paddle.position = Vec3d(0, 0.06, 0);
  paddle.angularVelocity = Vec3d(0, 6.0, 0);
  scene.colliders.push_back(paddle);
  Simulation sim(scene);
  ASSERT_GT(sim.boundary().size(), sim.boundary().staticCount());
  while (sim.time() < 0.5)
    sim.step();
  // angular momentum about the paddle's axis follows its spin
  double Ly = 0.0;
  const ParticleSet& p = sim.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    Ly += double(p.m[i]) * (p.x[i].cast<double>() - paddle.position).cross(p.v[i].cast<double>()).y();
  }
  EXPECT_GT(Ly, 1e-3);
  // and no fluid particle sits inside the paddle
  for (std::size_t i = 0; i < p.size(); ++i) {
    ColliderDesc now = paddle;
    now.orientation = sim.colliders()[1].orientation;
    EXPECT_GT(signedDistanceLocal(now, now.orientation.inverse() * (p.x[i].cast<double>() - now.position)),
              -0.004);
  }
}

TEST(PhysicsTest, InstabilityIsReportedWithStepAndParticle) {
  SceneDesc runaway = smallDamBreak();
  runaway.fluid[0].velocity = Vec3d(0, 80, 0);
  Simulation fast(runaway);
  try {
    fast.step();
    FAIL() << "no instability reported";
  } catch (const InstabilityError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("step 0"), std::string::npos) << msg;
    EXPECT_NE(msg.find("particle"), std::string::npos) << msg;
    EXPECT_NE(msg.find("max_speed"), std::string::npos) << msg;
  }

  SceneDesc open;
  open.params.particleRadius = 0.01;
  open.domain = Aabb(Vec3d(-0.2, -0.2, -0.2), Vec3d(0.2, 0.2, 0.2));
  open.fluid.push_back(FluidBlock{Aabb(Vec3d(-0.05, -0.05, -0.05), Vec3d(0.05, 0.05, 0.05)), Vec3d::Zero()});
  Simulation falling(open);
  try {
    while (falling.time() < 2.0)
      falling.step();
    FAIL() << "a particle left the domain unreported";
  } catch (const InstabilityError& e) {
    EXPECT_NE(std::string(e.what()).find("left the domain"), std::string::npos) << e.what();
  }
}

TEST(PhysicsTest, BadSceneIsRejected) {
  SceneDesc s = smallDamBreak();
  s.params.dtMin = 1.0;
  EXPECT_THROW(Simulation{s}, InputError);
  SceneDesc outside = smallDamBreak();
  outside.fluid[0].box = Aabb(Vec3d(0.5, 0.5, 0.5), Vec3d(0.9, 0.9, 0.9));
  EXPECT_THROW(Simulation{outside}, InputError);
}

TEST(PhysicsTest, NonFiniteNumbersInASceneBuiltInCodeAreNamed) {
  // (the fuzzer's own scene once left a block's velocity uninitialised with `{}`: the garbage surfaced as
  // an instability at step 0, and only for some heap contents)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto messageOf = [](const SceneDesc& s) -> std::string {
    try {
      Simulation sim(s);
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  SceneDesc velocity = smallDamBreak();
  velocity.fluid[0].velocity = Vec3d(0.0, nan, 0.0);
  EXPECT_NE(messageOf(velocity).find("fluid block 0 has a non-finite box or velocity"), std::string::npos)
      << messageOf(velocity);
  SceneDesc box = smallDamBreak();
  box.fluid[0].box.max().x() = std::numeric_limits<double>::infinity();
  EXPECT_NE(messageOf(box).find("fluid block 0"), std::string::npos) << messageOf(box);
  SceneDesc collider = smallDamBreak();
  ASSERT_FALSE(collider.colliders.empty());
  collider.colliders[0].name = "tank";
  collider.colliders[0].angularVelocity = Vec3d(nan, 0.0, 0.0);
  EXPECT_NE(messageOf(collider).find("collider 'tank' has a non-finite"), std::string::npos)
      << messageOf(collider);
  EXPECT_EQ(messageOf(smallDamBreak()), "accepted");
}

TEST(PhysicsTest, PlyRoundTripSmall) {
  Simulation sim(smallDamBreak());
  for (int k = 0; k < 5; ++k)
    sim.step();
  const std::string path = fp::test::tempPath("particles.ply");
  writePly(path, sim.particles());
  const ParticleSet back = readPly(path);
  ASSERT_EQ(back.size(), sim.particles().size());
  EXPECT_TRUE(bitIdentical(back, sim.particles()));
  EXPECT_EQ(back.m, sim.particles().m);
  EXPECT_THROW(readPly(path + ".missing"), InputError);
}

namespace {

/// Two slabs of water sliding past each other at +-u in x, no walls, no gravity: the laminar viscosity's
/// shear layer. Returns the fraction of its x-momentum the upper slab has lost after `time`.
double shearLayerMomentumLoss(double laminar, double xsph, double dtMax, double time, bool* energyRose) {
  const double u = 0.5;
  SceneDesc s;
  s.params.particleRadius = 0.008;
  s.params.gravity = {0, 0, 0};
  s.params.viscosity = xsph;
  s.params.laminarViscosity = laminar;
  s.params.dtMax = dtMax;
  s.domain = Aabb(Vec3d(-1, -1, -1), Vec3d(1, 1, 1));
  // the lattices of the two blocks meet one spacing apart, as within a block
  s.fluid.push_back(FluidBlock{Aabb(Vec3d(-0.2, -0.096, -0.1), Vec3d(0.2, 0.0, 0.1)), Vec3d(-u, 0, 0)});
  s.fluid.push_back(FluidBlock{Aabb(Vec3d(-0.2, -0.016, -0.1), Vec3d(0.2, 0.08, 0.1)), Vec3d(u, 0, 0)});
  Simulation sim(s);
  const ParticleSet& p = sim.particles();
  std::vector<std::uint8_t> upper(p.size(), 0);
  double upperMass = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    upper[p.id[i]] = p.v[i].x() > 0;
    upperMass += upper[p.id[i]] ? double(p.m[i]) : 0.0;
  }
  auto kinetic = [&] {
    double e = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      e += 0.5 * double(p.m[i]) * double(p.v[i].squaredNorm());
    return e;
  };
  const Vec3d p0 = sim.totalMomentum();
  double e = kinetic();
  *energyRose = false;
  while (sim.time() < time) {
    sim.step();
    const double next = kinetic();
    *energyRose = *energyRose || next > e * (1 + 1e-6);
    e = next;
  }
  EXPECT_LT((sim.totalMomentum() - p0).norm(), 1e-5 * upperMass * u);
  double upperMomentum = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    upperMomentum += upper[p.id[i]] ? double(p.m[i]) * double(p.v[i].x()) : 0.0;
  return 1.0 - upperMomentum / (upperMass * u);
}

}  // namespace

TEST(PhysicsTest, LaminarViscositySmallDiffusesAShearLayerAtItsRate) {
  // Two half-spaces at +-u exchange 2 rho u sqrt(nu t / pi) of momentum per unit area by time t (Stokes'
  // first problem); over a slab of thickness a that is a fraction 2 sqrt(nu t / pi) / a of its momentum:
  // 0.356 for nu = 0.01 m^2/s, t = 0.1 s, a = 0.1 m (the lattice spans 0.096 m).
  const double expected = 2.0 * std::sqrt(0.01 * 0.1 / 3.14159265) / 0.1;
  bool rose = false;
  const double laminar = shearLayerMomentumLoss(0.01, 0.0, 0.001, 0.1, &rose);
  EXPECT_FALSE(rose);
  // XSPH with the reference scene's 0.01 (what the reference dam break ran with before issue #12): a much
  // weaker coupling, which let thin jets run up the walls at twice the free-fall speed
  const double xsph = shearLayerMomentumLoss(0.0, 0.01, 0.001, 0.1, &rose);
  // At r = 8 mm and dt = 5 ms an explicit Laplacian of 0.01 m^2/s (damping rate ~840 1/s) would overshoot
  // and grow; the per-pair limit keeps it stable and dissipative
  const double limited = shearLayerMomentumLoss(0.01, 0.0, 0.005, 0.1, &rose);
  EXPECT_FALSE(rose);
  std::printf(
      "shear layer: momentum lost by the upper slab %.3f (laminar nu = 0.01, analytic %.3f), %.3f "
      "(XSPH 0.01), %.3f (laminar, 5 ms steps, limited)\n",
      laminar, expected, xsph, limited);
  EXPECT_NEAR(laminar, expected, 0.25 * expected);
  EXPECT_LT(xsph, 0.5 * laminar);
  EXPECT_GT(limited, 0.0);
}

TEST(PhysicsTest, UnderDenseLatticeSmallSettlesToRestDensityInItsShareOfTheVolume) {
  // lattice_density 0.8 (the reference library's particle mass, 0.8 (2r)^3 rho0): the same particles carry
  // 0.8 of the mass, the block starts under-dense, falls together under gravity and settles at rest density
  // in 0.8 of its volume, so its water stands 0.8 as high
  const double r = 0.1 / 10.4;
  auto settled = [&](double latticeDensity, double& mass, double& height, double& interiorDensity) {
    SceneDesc scene = tankScene(Vec3d(0.1, 0.15, 0.1), Vec3d(-0.1, 0, -0.1), Vec3d(0.1, 0.2, 0.1), r);
    scene.params.latticeDensity = latticeDensity;
    scene.params.initialRelaxation = 0;
    Simulation sim(scene);
    while (sim.time() < 1.0)
      sim.step();
    const ParticleSet& p = sim.particles();
    mass = sim.totalMass();
    // the water's height: its centre of mass above the bottom layer's centres (half the height between the
    // first and the last layer's centres, so it scales with the layers' spacing)
    double com = 0.0, bottom = 1e9;
    for (const Vec3& x : p.x) {
      com += double(x.y()) / double(p.size());
      bottom = std::min(bottom, double(x.y()));
    }
    height = com - bottom;
    double rhoSum = 0.0;
    int count = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.x[i].y() > 4 * r && p.x[i].y() < com && std::abs(p.x[i].x()) < 0.05 &&
          std::abs(p.x[i].z()) < 0.05) {
        rhoSum += double(p.rho[i]);
        ++count;
      }
    interiorDensity = count > 0 ? rhoSum / count / scene.params.restDensity : 0.0;
    return p.size();
  };
  double massFull, heightFull, rhoFull, massReference, heightReference, rhoReference;
  const std::size_t nFull = settled(1.0, massFull, heightFull, rhoFull);
  const std::size_t nReference = settled(0.8, massReference, heightReference, rhoReference);
  std::printf(
      "lattice density 1.0 / 0.8: %zu / %zu particles, mass %.4f / %.4f kg, water height %.4f / %.4f m "
      "(ratio %.3f), interior density %.4f / %.4f rho0\n",
      nFull, nReference, massFull, massReference, heightFull, heightReference, heightReference / heightFull,
      rhoFull, rhoReference);
  EXPECT_EQ(nFull, nReference);
  EXPECT_NEAR(massReference / massFull, 0.8, 1e-6);
  EXPECT_NEAR(rhoReference, 1.0, 0.01);
  EXPECT_NEAR(rhoFull, 1.0, 0.01);
  EXPECT_NEAR(heightReference / heightFull, 0.8, 0.02);
}
