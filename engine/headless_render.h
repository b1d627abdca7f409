#pragma once
/// The headless renderer: an OSMesa context with no display, the fluid renderer and a camera that frames the
/// scene; called with every frame of the headless run, it writes one PNG a frame, with the frame's splash
/// particles (sim/splash.h) drawn as spray unless the settings hide it (--no-spray, --set show_spray=false).

#include <memory>
#include <string>

#include "engine/cli.h"
#include "render/camera.h"
#include "sim/simulation.h"
#include "sim/splash.h"

namespace fp::render {
class OffscreenContext;
class FluidRenderer;
}  // namespace fp::render

namespace fp::engine {

/// Renders frames of a simulation to `DIR/frame_NNNNN.png`.
class HeadlessRender {
 public:
  /// Creates the output folder, the GL context and the renderer with the options' size, view and shaders.
  /// Throws sim::InputError for an unwritable folder and render::RenderError (ShaderError) for a missing or
  /// broken shader or no GL context.
  explicit HeadlessRender(const CliOptions& options);
  ~HeadlessRender();
  HeadlessRender(const HeadlessRender&) = delete;
  HeadlessRender& operator=(const HeadlessRender&) = delete;

  /// Renders the simulation's current state as frame `frame`; the first call frames the scene. The spray is
  /// `splash` when given (the caller already generated this frame's splash), else generated here from the
  /// simulation with frame index `frame`; nothing is generated or drawn when the spray is hidden.
  void renderFrame(int frame, const sim::Simulation& simulation,
                   const sim::SplashParticles* splash = nullptr);

  /// "OSMesa, 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (...)"
  const std::string& contextDescription() const;
  /// images written so far
  int imagesWritten() const { return m_written; }
  /// splash particles drawn in the last frame
  std::size_t sprayCount() const { return m_sprayCount; }
  /// mean wall time of rendering and writing one image [ms]
  double meanMilliseconds() const { return m_written ? m_totalMs / m_written : 0.0; }

 private:
  std::unique_ptr<render::OffscreenContext> m_context;
  std::unique_ptr<render::FluidRenderer> m_renderer;
  render::OrbitCamera m_camera;
  sim::SplashGenerator m_splash;
  std::size_t m_sprayCount = 0;
  bool m_framed = false;
  std::string m_outDir;
  int m_width = 0;
  int m_height = 0;
  int m_written = 0;
  double m_totalMs = 0;
};

/// The box a camera should frame: the union of the containers' world boxes, or the scene domain without one.
Eigen::AlignedBox3f sceneViewBox(const sim::Simulation& simulation);

}  // namespace fp::engine
