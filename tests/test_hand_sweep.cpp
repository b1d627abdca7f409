// The hand against the CFL step: swept through the water at the mouse hand's full speed, it leaves no fluid
// particle inside its colliders, in every resolution mode (issue #12). Lives with the engine tests because it
// drives the hand through fluid_input, which the physics tests do not link.
#include <gtest/gtest.h>

#include <algorithm>

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
