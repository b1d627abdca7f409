#pragma once
// Scenes built in code for the tests.

#include "sim/scene.h"

namespace fp::test {

/// A box container with its floor at y = 0 and water filling [waterLo, waterHi]; the domain is the tank plus
/// a margin of 5 cm.
inline sim::SceneDesc tankScene(const sim::Vec3d& half, const sim::Vec3d& waterLo, const sim::Vec3d& waterHi,
                                double radius) {
  sim::SceneDesc s;
  s.name = "test tank";
  s.params.particleRadius = radius;
  sim::ColliderDesc tank;
  tank.name = "tank";
  tank.shape = sim::ShapeType::Box;
  tank.container = true;
  tank.halfExtents = half;
  tank.position = sim::Vec3d(0, half.y(), 0);
  s.colliders.push_back(tank);
  s.fluid.push_back(sim::FluidBlock{sim::Aabb(waterLo, waterHi), sim::Vec3d::Zero()});
  s.domain = sim::Aabb(sim::Vec3d(-half.x(), 0, -half.z()) - sim::Vec3d::Constant(0.05),
                       sim::Vec3d(half.x(), 2 * half.y(), half.z()) + sim::Vec3d::Constant(0.05));
  return s;
}

/// Water at rest, 0.3 m deep in a 0.4 m tank at r = 0.2 / 20.4 m, fluidplaying with time levels
/// (time_levels = 2), under a sphere spinning in the air 5 cm above it (3.7 m/s at its surface): the sphere
/// sets a step of about 2 ms, which the water at rest may take twice, so particles are held.
inline sim::SceneDesc heldWaterScene() {
  sim::SceneDesc scene = tankScene(sim::Vec3d(0.2, 0.2, 0.2), sim::Vec3d(-0.2, 0.0, -0.2),
                                   sim::Vec3d(0.2, 0.3, 0.2), 0.2 / 20.4);
  scene.mode = sim::AdaptivityMode::FluidPlaying;
  scene.params.timeLevels = 2;
  sim::ColliderDesc spinner;
  spinner.name = "spinner";
  spinner.shape = sim::ShapeType::Sphere;
  spinner.radius = 0.02;
  spinner.position = sim::Vec3d(0.0, 0.37, 0.0);
  spinner.angularVelocity = sim::Vec3d(0.0, 0.0, 187.0);
  scene.colliders.push_back(spinner);
  return scene;
}

/// `s` with a sphere named "paddle" moving through it at a constant velocity: kinematic boundary particles
/// beside the static ones
inline sim::SceneDesc withPaddle(sim::SceneDesc s, double radius, const sim::Vec3d& position,
                                 const sim::Vec3d& velocity) {
  sim::ColliderDesc paddle;
  paddle.name = "paddle";
  paddle.shape = sim::ShapeType::Sphere;
  paddle.radius = radius;
  paddle.position = position;
  paddle.linearVelocity = velocity;
  s.colliders.push_back(paddle);
  return s;
}

}  // namespace fp::test
