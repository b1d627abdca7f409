#include "render/fluid_renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "render/collider_mesh.h"
#include "render/fluid_renderer_impl.h"
#include "render/render_error.h"
#include "sim/simulation.h"

namespace fp::render {

FrameData frameDataOf(const sim::Simulation& simulation, SpraySpan spray) {
  FrameData f;
  f.particles = &simulation.particles();
  f.time = simulation.time();
  f.spray = spray;
  f.colliders = &simulation.colliders();
  const sim::SceneDesc& scene = simulation.scene();
  f.bounds = Eigen::AlignedBox3f(scene.domain.min().cast<float>(), scene.domain.max().cast<float>());
  f.params = simulation.params();
  f.scales.restDensity = f.params.restDensity;
  // level 1 of the mass: a fine particle of radius r on the lattice of spacing 2r
  const double spacing = 2.0 * f.params.particleRadius;
  f.scales.fineMass = f.params.restDensity * spacing * spacing * spacing;
  return f;
}

namespace {

using Clock = std::chrono::steady_clock;

// A round step near `x`: 1, 2 or 5 times a power of ten.
float niceStep(float x) {
  const float p = std::pow(10.0f, std::floor(std::log10(std::max(x, 1e-6f))));
  const float m = x / p;
  return p * (m < 1.5f ? 1.0f : m < 3.5f ? 2.0f : m < 7.5f ? 5.0f : 10.0f);
}

Mat4 poseMatrix(const sim::Vec3d& position, const sim::Quatd& orientation) {
  Mat4 m = Mat4::Identity();
  m.block<3, 3>(0, 0) = orientation.normalized().toRotationMatrix().cast<float>();
  m.block<3, 1>(0, 3) = position.cast<float>();
  return m;
}

}  // namespace

FluidRenderer::Impl::Impl(const std::string& dir)
    : sky(dir, "fullscreen.vert", "sky.frag"),
      mesh(dir, "mesh.vert", "mesh.frag"),
      floor(dir, "mesh.vert", "floor.frag"),
      glass(dir, "mesh.vert", "glass.frag"),
      sphereDepth(dir, "sphere.vert", "sphere_depth.frag"),
      sphereWet(dir, "sphere.vert", "sphere_wet.frag"),
      sphereThickness(dir, "sphere.vert", "sphere_thickness.frag"),
      sphereColor(dir, "sphere.vert", "sphere_color.frag"),
      spray(dir, "sphere.vert", "spray.frag"),
      filter(dir, "fullscreen.vert", "depth_filter.frag"),
      depthDown(dir, "fullscreen.vert", "depth_down.frag"),
      depthUp(dir, "fullscreen.vert", "depth_up.frag"),
      composite(dir, "fullscreen.vert", "fluid_composite.frag"),
      overlay(dir, "overlay.vert", "overlay.frag") {
  sphereAttributes(particleVao, particleVbo);
  sphereAttributes(sprayVao, sprayVbo);
  sphereAttributes(wetVao, particleVbo);
  glBindVertexArray(wetVao.id);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, wetIndices.id);
  glBindVertexArray(0);
  overlayAttributes(overlayVao, overlayVbo);
  GLfloat range[2] = {1.0f, 64.0f};
  glGetFloatv(GL_POINT_SIZE_RANGE, range);
  maxPointSize = range[1];
  gl::checkError("FluidRenderer setup");
}

void FluidRenderer::Impl::resize(int w, int h) {
  if (w == width && h == height)
    return;
  width = w;
  height = h;
  sceneColor.create(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR);
  sceneDepth.create(GL_DEPTH_COMPONENT32F, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, GL_NEAREST);
  for (Texture& t : fluidDepth)
    t.create(GL_RG32F, w, h, GL_RG, GL_FLOAT, GL_NEAREST);
  // thickness varies slowly across the image: half resolution, read back with linear filtering
  halfWidth = (w + 1) / 2;
  halfHeight = (h + 1) / 2;
  thickness.create(GL_RG16F, halfWidth, halfHeight, GL_RG, GL_FLOAT, GL_LINEAR);
  for (Texture& t : halfDepth)
    t.create(GL_RGBA32F, halfWidth, halfHeight, GL_RGBA, GL_FLOAT, GL_LINEAR);
  finalColor.create(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST);
  finalDepth.create(GL_DEPTH_COMPONENT32F, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, GL_NEAREST);
  sceneFbo.build(sceneColor, &sceneDepth, "scene");
  // the depth pass tests against and writes into the scene's depth
  depthFbo.build(fluidDepth[0], &sceneDepth, "fluid depth");
  filterFbo[0].build(fluidDepth[0], nullptr, "filter 0");
  filterFbo[1].build(fluidDepth[1], nullptr, "filter 1");
  halfFbo[0].build(halfDepth[0], nullptr, "half filter 0");
  halfFbo[1].build(halfDepth[1], nullptr, "half filter 1");
  // the thickness pass samples the scene's depth instead of testing against it (other size)
  thicknessFbo.build(thickness, nullptr, "thickness");
  finalFbo.build(finalColor, &finalDepth, "final");
}

void FluidRenderer::Impl::updateColliders(const std::vector<sim::ColliderState>& states) {
  colliders.resize(states.size());
  for (std::size_t k = 0; k < states.size(); ++k) {
    const sim::ColliderDesc& d = states[k].desc;
    auto& c = colliders[k];
    const bool same = c && c->desc.shape == d.shape && c->desc.halfExtents == d.halfExtents &&
                      c->desc.radius == d.radius && c->desc.halfLength == d.halfLength &&
                      c->desc.mesh == d.mesh && c->desc.container == d.container;
    if (!same) {
      c = std::make_unique<Collider>();
      const MeshData m = colliderMesh(d);
      meshAttributes(c->vao, c->vbo, m);
      c->vertices = GLsizei(m.vertexCount());
    }
    c->desc = d;
    c->model = poseMatrix(states[k].position, states[k].orientation);
  }
}

void FluidRenderer::Impl::updateFloor(const FrameData& frame) {
  Eigen::AlignedBox3f box = frame.bounds;
  floorY = box.min().y();
  if (frame.colliders) {
    bool first = true;
    for (const sim::ColliderState& s : *frame.colliders) {
      if (!s.desc.container)
        continue;
      // the container's world box, from its eight rotated corners
      Eigen::AlignedBox3f c;
      for (int k = 0; k < 8; ++k) {
        const sim::Vec3d h = s.desc.halfExtents;
        const sim::Vec3d corner(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z());
        c.extend((s.position + s.orientation * corner).cast<float>());
      }
      box = first ? c : box.merged(c);
      floorY = first ? c.min().y() : std::min(floorY, c.min().y());
      first = false;
    }
  }
  center = box.center();
  sceneSize = std::max(box.sizes().maxCoeff(), 1e-3f);
  floorHalf = 6.0f * sceneSize;
  floorTile = niceStep(sceneSize / 8.0f);
  // a floor just below the container's bottom, so the two never fight for depth
  const float y = floorY - 1e-3f * sceneSize;
  MeshData quad;
  const float h = floorHalf;
  const float corners[6][2] = {{-h, -h}, {-h, h}, {h, h}, {-h, -h}, {h, h}, {h, -h}};
  for (const auto& xz : corners) {
    quad.vertices.insert(quad.vertices.end(), {center.x() + xz[0], y, center.z() + xz[1], 0.0f, 1.0f, 0.0f});
  }
  meshAttributes(floorVao, floorVbo, quad);
}

const FluidRenderer::Impl::Collider* FluidRenderer::Impl::container() const {
  for (const auto& c : colliders) {
    if (c->desc.container)
      return c.get();
  }
  return nullptr;
}

void FluidRenderer::Impl::updateWet(const FrameData& frame, float reach) {
  wetCount = 0;
  wetFaces.fill({0, 0});
  const Collider* box = container();
  if (!box || !frame.particles || reach <= 0.0f)
    return;
  const sim::ParticleSet& p = *frame.particles;
  const Mat4 toLocal = box->model.inverse();
  const Eigen::Vector3f half = box->desc.halfExtents.cast<float>();
  // one list a side (-x, +x, -z, +z); renderView draws those of the sides that face the eye
  std::array<std::vector<std::uint32_t>, 4> lists;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3f local = (toLocal * Eigen::Vector3f(p.x[i].cast<float>()).homogeneous()).head<3>();
    const float r = reach * 0.25f * float(p.H[i]);
    if (local.x() < -half.x() + r)
      lists[0].push_back(std::uint32_t(i));
    if (local.x() > half.x() - r)
      lists[1].push_back(std::uint32_t(i));
    if (local.z() < -half.z() + r)
      lists[2].push_back(std::uint32_t(i));
    if (local.z() > half.z() - r)
      lists[3].push_back(std::uint32_t(i));
  }
  wetStaging.clear();
  for (int f = 0; f < 4; ++f) {
    wetFaces[std::size_t(f)] = {wetStaging.size(), lists[std::size_t(f)].size()};
    wetStaging.insert(wetStaging.end(), lists[std::size_t(f)].begin(), lists[std::size_t(f)].end());
  }
  wetCount = wetStaging.size();
  glBindVertexArray(0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, wetIndices.id);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(wetCount * sizeof(std::uint32_t)), wetStaging.data(),
               GL_STREAM_DRAW);
}

FluidRenderer::FluidRenderer(const std::string& shaderDir) : m_impl(std::make_unique<Impl>(shaderDir)) {}

FluidRenderer::~FluidRenderer() = default;

std::size_t FluidRenderer::particleCount() const {
  return m_impl->particleCount;
}

std::vector<float> FluidRenderer::readSurfaceDepth() const {
  const Impl& r = *m_impl;
  std::vector<float> rg(std::size_t(r.width) * std::size_t(r.height) * 2);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.filterFbo[r.surface].id);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, r.width, r.height, GL_RG, GL_FLOAT, rg.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  gl::checkError("FluidRenderer::readSurfaceDepth");
  std::vector<float> depth(rg.size() / 2);
  for (std::size_t k = 0; k < depth.size(); ++k)
    depth[k] = rg[2 * k];
  return depth;
}

void FluidRenderer::update(const FrameData& frame) {
  Impl& r = *m_impl;
  const RenderSettings& s = m_settings;
  r.legendField = s.colorField;
  r.legendRange = s.autoRange ? defaultColorRange(s.colorField, frame.params) : s.colorRange;

  // particles: centre, draw radius H/4, time since split, colour coordinate
  r.particleCount = 0;
  r.maxRadius = 0.0f;
  if (frame.particles) {
    const sim::ParticleSet& p = *frame.particles;
    const std::size_t n = p.size();
    const bool colors = s.view == RenderSettings::View::Particles;
    r.staging.resize(n * kSphereFloats);
    for (std::size_t i = 0; i < n; ++i) {
      float* o = &r.staging[i * kSphereFloats];
      o[0] = p.x[i].x();
      o[1] = p.x[i].y();
      o[2] = p.x[i].z();
      o[3] = 0.25f * p.H[i];
      const float splitTime = p.splitTimeOf(i);
      o[4] = splitTime >= 0.0f ? float(frame.time - double(splitTime)) : -1.0f;
      o[5] = colors ? normalizeColorValue(colorFieldValue(s.colorField, p, i, frame.scales), r.legendRange)
                    : 0.0f;
      r.maxRadius = std::max(r.maxRadius, o[3]);
    }
    glBindBuffer(GL_ARRAY_BUFFER, r.particleVbo.id);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(r.staging.size() * sizeof(float)), r.staging.data(),
                 GL_STREAM_DRAW);
    r.particleCount = n;
  }
  // spray: same layout, never highlighted
  r.sprayCount = frame.spray.count;
  if (frame.spray.count) {
    r.staging.resize(frame.spray.count * kSphereFloats);
    for (std::size_t i = 0; i < frame.spray.count; ++i) {
      float* o = &r.staging[i * kSphereFloats];
      o[0] = frame.spray.positions[i].x();
      o[1] = frame.spray.positions[i].y();
      o[2] = frame.spray.positions[i].z();
      o[3] = frame.spray.radii[i];
      o[4] = -1.0f;
      o[5] = 0.0f;
    }
    glBindBuffer(GL_ARRAY_BUFFER, r.sprayVbo.id);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(r.staging.size() * sizeof(float)), r.staging.data(),
                 GL_STREAM_DRAW);
  }
  r.fineRadius = float(frame.params.particleRadius);
  if (r.maxRadius <= 0.0f)
    r.maxRadius = r.fineRadius;
  r.updateColliders(frame.colliders ? *frame.colliders : std::vector<sim::ColliderState>{});
  r.updateFloor(frame);
  r.updateWet(frame, s.wetReach);
  gl::checkError("FluidRenderer::update");
}

void FluidRenderer::renderView(const Mat4& view, const Mat4& projection, const RenderTarget& target) {
  Impl& r = *m_impl;
  const RenderSettings& s = m_settings;
  if (target.width <= 0 || target.height <= 0)
    throw RenderError("renderView: empty target rectangle");
  r.resize(target.width, target.height);
  m_times = PassTimes{};
  auto last = Clock::now();
  auto mark = [&](double& slot) {
    if (!s.profile)
      return;
    glFinish();
    const auto now = Clock::now();
    slot += std::chrono::duration<double, std::milli>(now - last).count();
    last = now;
  };

  ViewParams v;
  v.view = view;
  v.projection = projection;
  v.invView = view.inverse();
  v.eye = v.invView.block<3, 1>(0, 3);
  v.settings = &s;
  v.highlight = s.highlightSplits ? s.highlightDuration : 0.0f;
  const bool fluidView = s.view == RenderSettings::View::Fluid;
  glViewport(0, 0, r.width, r.height);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);

  r.drawScene(v, fluidView ? r.sceneFbo.id : r.finalFbo.id);
  mark(m_times.scene);
  if (fluidView) {
    r.drawThickness(v);
    mark(m_times.thickness);
    r.drawDepth(v);
    mark(m_times.depth);
    r.filterDepth(v);
    mark(m_times.filter);
    r.drawComposite(v);
    mark(m_times.composite);
  } else {
    r.drawParticleView(v);
    mark(m_times.composite);
  }
  r.drawOverlay(v);
  glDisable(GL_DEPTH_TEST);
  if (!fluidView)
    r.drawLegend();
  glBindFramebuffer(GL_READ_FRAMEBUFFER, r.finalFbo.id);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, target.framebuffer);
  glBlitFramebuffer(0, 0, r.width, r.height, target.x, target.y, target.x + target.width,
                    target.y + target.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  glBindVertexArray(0);
  glUseProgram(0);
  mark(m_times.overlay);
  gl::checkError("FluidRenderer::renderView");
}

}  // namespace fp::render
