#pragma once
// The scenes of issue 14's look tests, from particle states exported by the simulation (tests/gl/data/):
//   hand_tank_rest_*.ply   assets/scenes/hand_tank.json, no hand, frame 90 (1.5 s), --mode uniform-high or
//                          fluidplaying: `fluidplaying --headless --scene assets/scenes/hand_tank.json --mode
//                          M
//                          --frames 90 --export DIR`
//   propeller_moving.ply   assets/scenes/propeller.json, fluidplaying, frame 60 (1 s): fine and coarse
//                          particles stirred by the propeller
// The camera is the headless renderer's: it frames the tank at yaw 0.6, pitch 0.35 rad.

#include <cstdlib>
#include <string>

#include "render/render_settings.h"
#include "water_metrics.h"

namespace fp::test {

struct LookScene {
  SyntheticScene state;
  float fineRadius = 0.0079f;  // [m]
  float surfaceY = 0.0f;       // simulated free surface [m]
  Eigen::AlignedBox2f inner;   // x-z region of the free surface measured, away from the walls
};

inline std::string lookDataDir() {
  return std::string(FP_GL_TEST_DIR) + "/data";
}

inline LookScene restingHandTank(bool adaptive) {
  LookScene s;
  const Eigen::Vector3f tank(0.28f, 0.15f, 0.1849f);
  s.state = loadTankState(
      lookDataDir() + (adaptive ? "/hand_tank_rest_fluidplaying.ply" : "/hand_tank_rest_uniform_high.ply"),
      tank, s.fineRadius);
  // four fine spacings from the walls, where the surface meets the glass
  const float margin = 8.0f * s.fineRadius;
  s.inner = Eigen::AlignedBox2f(Eigen::Vector2f(-tank.x() + margin, -tank.z() + margin),
                                Eigen::Vector2f(tank.x() - margin, tank.z() - margin));
  s.surfaceY = simulatedSurfaceHeight(s.state.particles, s.fineRadius, s.inner);
  return s;
}

inline LookScene movingPropeller() {
  LookScene s;
  s.fineRadius = 0.0088f;
  const Eigen::Vector3f tank(0.4f, 0.3f, 0.25f);
  s.state = loadTankState(lookDataDir() + "/propeller_moving.ply", tank, s.fineRadius);
  s.inner = Eigen::AlignedBox2f(Eigen::Vector2f(-tank.x(), -tank.z()), Eigen::Vector2f(tank.x(), tank.z()));
  return s;
}

// One rendering: the image, the filtered depth and the surface reconstructed from it.
struct LookShot {
  render::Image image;
  std::vector<float> depth;
  DepthSurface surface{{}, 0, 0, render::Mat4::Identity(), render::Mat4::Identity()};
};

inline LookShot shoot(render::FluidRenderer& renderer, const LookScene& scene, int width, int height) {
  const float aspect = float(width) / float(height);
  const render::OrbitCamera camera = frameCamera(scene.state, aspect);
  renderer.update(scene.state.frame(false));
  render::RenderTarget target;
  target.width = width;
  target.height = height;
  renderer.renderView(camera.view(), camera.projection(aspect), target);
  LookShot shot;
  shot.image = render::readFramebuffer(0, 0, 0, width, height);
  shot.depth = renderer.readSurfaceDepth();
  shot.surface = DepthSurface(shot.depth, width, height, camera.view(), camera.projection(aspect));
  return shot;
}

// KEY=VALUE of the render settings table (filter_radius=6, ...) or of the internal members filter_max_taps
// and wet_reach (experiments of fp_water_look and fp_bench_render); "" or the error.
inline std::string applySetting(render::RenderSettings& s, const std::string& assignment) {
  const auto eq = assignment.find('=');
  const std::string name = assignment.substr(0, eq);
  const float v = eq == std::string::npos ? 0.0f : std::strtof(assignment.c_str() + eq + 1, nullptr);
  if (name == "filter_max_taps") {
    s.filterMaxTaps = std::max(1, int(v));
    return "";
  }
  if (name == "wet_reach") {
    s.wetReach = v;
    return "";
  }
  return render::RenderSettingsTable::get().assign(s, assignment);
}

}  // namespace fp::test
