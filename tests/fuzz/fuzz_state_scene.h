#pragma once
// The state fuzzer's scene (tests/fuzz/fuzz_state.cpp), shared with the unit test that checks the fuzzer's
// seed still decodes (StateIoErrors.TheStateFuzzersSeedIsFresh), so that a change to the parameter table or
// the format that makes tests/fuzz/state/seed.bin stale fails in the default test suite, not only in CI's
// fuzz stage.

#include "sim/scene.h"

namespace fp::test {

/// a small fluidplaying tank with a driven sphere, mass ratio 8, r = 2 cm
inline fp::sim::SceneDesc fuzzStateScene() {
  fp::sim::SceneDesc s;
  s.name = "fuzz tank";
  s.mode = fp::sim::AdaptivityMode::FluidPlaying;
  s.params.particleRadius = 0.02;
  s.params.massRatio = 8.0;
  s.params.initialRelaxation = 2;
  fp::sim::ColliderDesc tank;
  tank.name = "tank";
  tank.container = true;
  tank.halfExtents = fp::sim::Vec3d(0.12, 0.1, 0.08);
  tank.position = fp::sim::Vec3d(0, 0.1, 0);
  s.colliders.push_back(tank);
  fp::sim::ColliderDesc hand;
  hand.name = "hand";
  hand.shape = fp::sim::ShapeType::Sphere;
  hand.radius = 0.03;
  hand.position = fp::sim::Vec3d(0, 0.16, 0);
  hand.driven = true;
  s.colliders.push_back(hand);
  // (the velocity keeps its default of zero: `{}` for an Eigen vector would leave it uninitialised)
  fp::sim::FluidBlock block;
  block.box = fp::sim::Aabb(fp::sim::Vec3d(-0.12, 0, -0.08), fp::sim::Vec3d(0.12, 0.1, 0.08));
  s.fluid.push_back(block);
  s.domain = fp::sim::Aabb(fp::sim::Vec3d(-0.2, -0.05, -0.15), fp::sim::Vec3d(0.2, 0.3, 0.15));
  return s;
}

}  // namespace fp::test
