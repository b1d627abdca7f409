#include "engine/headless_render.h"

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "render/fluid_renderer.h"
#include "render/image.h"
#include "render/offscreen_context.h"
#include "render/shader_program.h"

namespace fp::engine {

Eigen::AlignedBox3f sceneViewBox(const sim::Simulation& simulation) {
  Eigen::AlignedBox3f box;
  for (const sim::ColliderState& c : simulation.colliders()) {
    if (!c.desc.container)
      continue;
    const sim::Vec3d h = c.desc.halfExtents;
    for (int k = 0; k < 8; ++k) {
      const sim::Vec3d corner(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z());
      box.extend((c.position + c.orientation * corner).cast<float>());
    }
  }
  if (box.isEmpty()) {
    const sim::Aabb& d = simulation.scene().domain;
    box = Eigen::AlignedBox3f(d.min().cast<float>(), d.max().cast<float>());
  }
  return box;
}

HeadlessRender::HeadlessRender(const CliOptions& options)
    : m_outDir(options.outDir), m_width(options.width), m_height(options.height) {
  std::error_code ec;
  std::filesystem::create_directories(m_outDir, ec);
  if (ec || !std::filesystem::is_directory(m_outDir))
    throw sim::InputError(m_outDir + ": cannot create the image directory" +
                          (ec ? " (" + ec.message() + ")" : ""));
  m_context = std::make_unique<render::OffscreenContext>(m_width, m_height);
  m_renderer = std::make_unique<render::FluidRenderer>(options.shaderDir.empty() ? render::defaultShaderDir()
                                                                                 : options.shaderDir);
  applyRenderOptions(options, m_renderer->settings());
}

HeadlessRender::~HeadlessRender() = default;

const std::string& HeadlessRender::contextDescription() const {
  return m_context->description();
}

void HeadlessRender::renderFrame(int frame, const sim::Simulation& simulation,
                                 const sim::SplashParticles* splash) {
  const auto start = std::chrono::steady_clock::now();
  const float aspect = float(m_width) / float(m_height);
  if (!m_framed) {
    const Eigen::AlignedBox3f box = sceneViewBox(simulation);
    m_camera.frame(box.min(), box.max(), aspect);
    m_framed = true;
  }
  render::SpraySpan spray;
  if (m_renderer->settings().showSpray) {
    const sim::SplashParticles& s = splash ? *splash : m_splash.generate(simulation, std::uint64_t(frame));
    spray = render::SpraySpan{s.x.data(), s.radius.data(), s.size()};
  }
  m_sprayCount = spray.count;
  m_renderer->update(render::frameDataOf(simulation, spray));
  render::RenderTarget target;
  target.width = m_width;
  target.height = m_height;
  m_renderer->renderView(m_camera.view(), m_camera.projection(aspect), target);
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%05d.png", frame);
  render::writePng((std::filesystem::path(m_outDir) / name).string(),
                   render::readFramebuffer(0, 0, 0, m_width, m_height));
  ++m_written;
  m_totalMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace fp::engine
