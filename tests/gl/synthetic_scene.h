#pragma once
// Scenes built in code for the image tests and the renderer benchmark: a block of fluid particles on a
// lattice in a glass container, with a camera that frames the container.

#include <cmath>
#include <functional>
#include <vector>

#include "render/camera.h"
#include "render/fluid_renderer.h"
#include "sim/particle_set.h"
#include "sim/scene.h"

namespace fp::test {

struct SyntheticScene {
  sim::ParticleSet particles;
  std::vector<sim::ColliderState> colliders;
  std::vector<sim::Vec3> sprayPositions;
  std::vector<sim::Real> sprayRadii;
  sim::SimParams params;
  double time = 1.0;
  Eigen::AlignedBox3f bounds;

  render::FrameData frame(bool withSpray = true) const {
    render::FrameData f;
    f.particles = &particles;
    f.time = time;
    f.colliders = &colliders;
    f.bounds = bounds;
    f.params = params;
    const double spacing = 2.0 * params.particleRadius;
    f.scales.fineMass = params.restDensity * spacing * spacing * spacing;
    f.scales.restDensity = params.restDensity;
    if (withSpray && !sprayPositions.empty())
      f.spray = render::SpraySpan{sprayPositions.data(), sprayRadii.data(), sprayPositions.size()};
    return f;
  }
};

// Puts an open box container of half size `tank` standing on y = 0 into the scene and frames the scene's
// bounds on it.
inline void addBoxTank(SyntheticScene& s, const Eigen::Vector3f& tank) {
  sim::ColliderState tankState;
  tankState.desc.name = "tank";
  tankState.desc.shape = sim::ShapeType::Box;
  tankState.desc.container = true;
  tankState.desc.halfExtents = tank.cast<double>();
  tankState.desc.position = sim::Vec3d(0.0, tank.y(), 0.0);
  tankState.position = tankState.desc.position;
  s.colliders.push_back(tankState);
  s.bounds = Eigen::AlignedBox3f(Eigen::Vector3f(-tank.x(), 0.0f, -tank.z()),
                                 Eigen::Vector3f(tank.x(), 2.0f * tank.y(), tank.z()));
}

// A water block [lo, hi] of radius-r particles (spacing 2r, support 4r) in a container of half size `tank`
// standing on y = 0. Particles left of x = splitX are marked as split at time - 0.1 s; with a `surface`, only
// particles below surface(x, z) are kept.
inline SyntheticScene makeBlockScene(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float r,
                                     const Eigen::Vector3f& tank, float splitX = -1e30f,
                                     const std::function<float(float, float)>& surface = {}) {
  SyntheticScene s;
  s.params.particleRadius = r;
  s.params.restDensity = 1000.0;
  const float d = 2.0f * r;
  const int nx = std::max(1, int(std::floor((hi.x() - lo.x()) / d)));
  const int ny = std::max(1, int(std::floor((hi.y() - lo.y()) / d)));
  const int nz = std::max(1, int(std::floor((hi.z() - lo.z()) / d)));
  s.particles.reserve(std::size_t(nx) * ny * nz);
  const float mass = 1000.0f * d * d * d;
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nz; ++k) {
        const sim::Vec3 x = lo + sim::Vec3(r + d * i, r + d * j, r + d * k);
        if (surface && x.y() > surface(x.x(), x.z()))
          continue;
        const std::size_t p = s.particles.add(x, sim::Vec3::Zero(), mass, 4.0f * r, 1000.0f);
        if (x.x() < splitX) {
          s.particles.splitTime[p] = float(s.time - 0.1);
          s.particles.flags[p] |= sim::kFlagSplit;
        }
        // a smooth variation for the particle view's colour fields
        s.particles.levelNu[p] = 1.0f + 7.0f * float(j) / float(std::max(1, ny - 1));
        s.particles.v[p] = sim::Vec3(0.0f, 2.0f * float(i) / float(std::max(1, nx - 1)), 0.0f);
      }
    }
  }
  addBoxTank(s, tank);
  return s;
}

// A camera framing the scene's container at the given aspect ratio.
inline render::OrbitCamera frameCamera(const SyntheticScene& s, float aspect) {
  render::OrbitCamera camera;
  camera.frame(s.bounds.min(), s.bounds.max(), aspect);
  return camera;
}

}  // namespace fp::test
