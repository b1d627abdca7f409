// The hand against the CFL step: swept through the water at the mouse hand's full speed, it leaves no fluid
// particle inside its colliders, in every resolution mode (issue #12). And the hands against split
// children's blending: a lost hand that comes back throws no water. Lives with the engine tests because it
// drives the hand through fluid_input, which the physics tests do not link.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>

#include "engine/cli.h"
#include "engine/headless_runner.h"
#include "input/hand_driver.h"
#include "sim/signed_distance.h"
#include "sim/simulation.h"
#include "tests/scene_fixtures.h"

using namespace fp::sim;
using fp::test::tankScene;

TEST(PhysicsTest, HandSweptAtFullSpeedLeavesNoWaterInsideInEveryMode) {
  // The mouse hand moves at up to 2.5 m/s: 12.5 mm in a 5 ms step, more than a particle's diameter against
  // a single layer of boundary particles. The CFL step counts the colliders' speed, so no water is left
  // inside the hand after it sweeps through the tank, whatever the resolution mode.
  const double speed = 2.5;
  for (AdaptivityMode mode : {AdaptivityMode::UniformLow, AdaptivityMode::UniformHigh,
                              AdaptivityMode::Surface, AdaptivityMode::FluidPlaying}) {
    SceneDesc scene =
        tankScene(Vec3d(0.25, 0.15, 0.12), Vec3d(-0.25, 0.0, -0.12), Vec3d(0.25, 0.1, 0.12), 0.008);
    scene.mode = mode;
    const fp::input::HandModel model;
    fp::input::HandPose start;
    // fingertips 2 cm above the floor, the hand beside the water's left end
    start.position = Vec3d(-0.17, 0.02 + model.reachBelowPalm(), 0.0);
    fp::input::HandPose end = start;
    end.position.x() = 0.17;
    // the lattice is built with the hand out of the water, then it plunges in and sweeps at full speed
    fp::input::HandPose above = start;
    above.position.y() += 0.2;
    const fp::input::HandDriver hand = fp::input::HandDriver::attach(scene, model, above);
    Simulation sim(scene);
    fp::input::PoseTrack track;
    track.add(fp::input::poseSampleOf(0.0, above));
    track.add(fp::input::poseSampleOf(0.2 / speed, start));
    track.add(fp::input::poseSampleOf(0.2 / speed + 0.34 / speed, end));
    const double tEnd = 0.2 / speed + 0.34 / speed;
    while (sim.time() < tEnd) {
      hand.apply(sim, track, 0.0, std::max(1e-4, sim.lastStep().dt));
      sim.step();
    }
    const ParticleSet& p = sim.particles();
    std::size_t inside = 0;
    for (std::size_t c = hand.firstCollider(); c < sim.colliders().size(); ++c) {
      const ColliderState& cs = sim.colliders()[c];
      for (std::size_t i = 0; i < p.size(); ++i) {
        const Vec3d local = cs.orientation.conjugate() * (p.x[i].cast<double>() - cs.position);
        if (signedDistanceLocal(cs.desc, local) < 0.0)
          ++inside;
      }
    }
    EXPECT_EQ(inside, 0u) << "mode " << modeName(mode) << ": " << inside
                          << " fluid particles inside the hand";
    EXPECT_GT(sim.stepCount(), std::uint64_t(tEnd / 0.005 * 1.5))
        << "the hand's speed should shorten the steps";
  }
}

namespace {

/// the largest fluid speed over the frames of the two-hand replay with a lost hand (the coarse hand tank,
/// 1.1 s), with split children's densities blended over `blendSteps` steps
double lostHandReplayTopSpeed(int blendSteps, unsigned seed) {
  const fp::engine::ThreadLimit threads(2);
  fp::engine::CliOptions o;
  o.headless = true;
  o.quiet = true;
  o.scenePath = std::string(FP_SOURCE_DIR) + "/assets/scenes/hand_tank_coarse.json";
  o.handScript = std::string(FP_SOURCE_DIR) + "/assets/hands/two_hands_lost.csv";
  o.frames = 66;
  o.seed = seed;
  o.sets = {"split_blend_steps=" + std::to_string(blendSteps)};
  std::ostringstream out, progress;
  double top = 0.0;
  const fp::engine::RunSummary s =
      fp::engine::runHeadless(o, out, progress, [&](int, const Simulation& sim, const SplashParticles&) {
        for (const Vec3& v : sim.particles().v)
          top = std::max(top, double(v.norm()));
      });
  EXPECT_EQ(s.status, "ok") << s.message;
  return top;
}

}  // namespace

TEST(PhysicsTest, BlendedSplitsThrowNoWaterWhenALostHandComesBack) {
  // Temporal blending (split_blend_steps, off by default) once threw water out of the two-hand replay with a
  // lost hand: a particle at 100 m/s, and later 4.9 m/s where the run without blending stays under 2.7 m/s.
  // The parent's density missed the outer shell of its support and read 10-25 % low, and blending compressed
  // children down hid their compression until the blend ended (docs/method.md, Temporal blending). With the
  // whole support and a blend that only lifts, the fastest water stays within 0.8 m/s of the plain run's in
  // every frame's maximum (measured: seed 3 2.29 against 2.02 m/s, seed 4 1.81 against 2.09; with the whole
  // support but blending both ways 3.17 and 3.24).
  for (unsigned seed : {3u, 4u}) {
    const double plain = lostHandReplayTopSpeed(0, seed);
    const double blended = lostHandReplayTopSpeed(10, seed);
    std::printf("seed %u: fastest water %.2f m/s without blending, %.2f m/s with split_blend_steps = 10\n",
                seed, plain, blended);
    EXPECT_LT(blended, plain + 0.8) << "seed " << seed;
  }
}
