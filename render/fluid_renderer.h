#pragma once
/// Screen-space fluid rendering (van der Laan et al. 2009; narrow-range depth filter of Truong and Yuksel
/// 2018) of a read-only view of the simulation, with split children tinted red, spray, a particle inspection
/// view and the scene's colliders. One call, renderView, draws one view: the desktop window, each VR eye and
/// the headless mode use it. Upload a frame once with update(), then draw it from as many views as needed.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/particle_colors.h"
#include "render/render_settings.h"
#include "sim/boundary_set.h"
#include "sim/particle_set.h"

namespace fp::sim {
class Simulation;
}

namespace fp::render {

/// Splash particles, drawn as spray: a plain span of positions and radii owned by the caller.
struct SpraySpan {
  const sim::Vec3* positions = nullptr;  ///< [m]
  const sim::Real* radii = nullptr;      ///< [m], > 0
  std::size_t count = 0;                 ///< number of spray particles
};

/// One frame of the simulation as the renderer sees it; every pointer is read, never written, and only during
/// update().
struct FrameData {
  const sim::ParticleSet* particles = nullptr;  ///< fluid particles; draw radius H / 4
  double time = 0.0;                            ///< simulated time [s], for the split highlight
  SpraySpan spray;                              ///< splash particles
  const std::vector<sim::ColliderState>* colliders = nullptr;  ///< shapes and current poses
  Eigen::AlignedBox3f bounds{Eigen::Vector3f(-1, -1, -1), Eigen::Vector3f(1, 1, 1)};  ///< scene domain [m]
  FieldScales scales;     ///< mass and density of the colour fields
  sim::SimParams params;  ///< ranges of the level fields
};

/// The frame of a simulation: particles, colliders, time, domain and the scales of the colour fields.
FrameData frameDataOf(const sim::Simulation& simulation, SpraySpan spray = {});

/// Where renderView draws: a framebuffer (0: the context's) and a viewport rectangle in it [px].
struct RenderTarget {
  unsigned framebuffer = 0;  ///< GL framebuffer name
  int x = 0;                 ///< viewport left [px]
  int y = 0;                 ///< viewport bottom [px]
  int width = 1;             ///< [px], > 0
  int height = 1;            ///< [px], > 0
};

/// Wall time of the passes of the last renderView, filled when RenderSettings::profile is on [ms].
struct PassTimes {
  double scene = 0;      ///< background, floor, colliders
  double thickness = 0;  ///< additive thickness of every particle
  double depth = 0;      ///< sphere-impostor depth
  double filter = 0;     ///< narrow-range depth filter
  double composite = 0;  ///< normals and shading (or the particle view's spheres)
  double overlay = 0;    ///< spray, glass, legend, copy to the target
  /// sum of the passes
  double total() const { return scene + thickness + depth + filter + composite + overlay; }
};

/// The renderer. Owns GL objects: create, use and destroy it with the same GL context current.
class FluidRenderer {
 public:
  /// Compiles the shaders of `shaderDir`; throws ShaderError naming the file and line of a missing or broken
  /// one.
  explicit FluidRenderer(const std::string& shaderDir);
  ~FluidRenderer();
  FluidRenderer(const FluidRenderer&) = delete;
  FluidRenderer& operator=(const FluidRenderer&) = delete;

  /// drawing options
  RenderSettings& settings() { return m_settings; }
  /// drawing options
  const RenderSettings& settings() const { return m_settings; }

  /// Uploads one frame (particles, spray, collider poses). Reads `frame` only; keeps no pointer into it.
  void update(const FrameData& frame);
  /// Draws the last uploaded frame seen through `view` and `projection` into `target`.
  void renderView(const Mat4& view, const Mat4& projection, const RenderTarget& target);

  /// pass times of the last renderView (RenderSettings::profile)
  const PassTimes& passTimes() const { return m_times; }
  /// particles uploaded by the last update()
  std::size_t particleCount() const;

 private:
  void drawLegend();
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  RenderSettings m_settings;
  PassTimes m_times;
};

}  // namespace fp::render
