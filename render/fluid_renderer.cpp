#include "render/fluid_renderer.h"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "render/collider_mesh.h"
#include "render/gl_api.h"
#include "render/render_error.h"
#include "render/shader_program.h"
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

// Owners of GL names; the renderer's GL context must be current when they die.
struct Texture {
  GLuint id = 0;
  Texture() = default;
  Texture(const Texture&) = delete;
  Texture& operator=(const Texture&) = delete;
  ~Texture() {
    if (id)
      glDeleteTextures(1, &id);
  }
  void create(GLint internalFormat, int width, int height, GLenum format, GLenum type, GLint filter) {
    if (!id)
      glGenTextures(1, &id);
    glBindTexture(GL_TEXTURE_2D, id);
    glTexImage2D(GL_TEXTURE_2D, 0, internalFormat, width, height, 0, format, type, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
};

struct Framebuffer {
  GLuint id = 0;
  Framebuffer() = default;
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;
  ~Framebuffer() {
    if (id)
      glDeleteFramebuffers(1, &id);
  }
  // (re)builds the framebuffer from a colour texture and an optional depth texture
  void build(const Texture& color, const Texture* depth, const char* name) {
    if (!id)
      glGenFramebuffers(1, &id);
    glBindFramebuffer(GL_FRAMEBUFFER, id);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color.id, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth ? depth->id : 0, 0);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      char code[16];
      std::snprintf(code, sizeof(code), "0x%04x", status);
      throw RenderError(std::string("framebuffer '") + name + "' is incomplete (" + code + ")");
    }
  }
};

struct Buffer {
  GLuint id = 0;
  Buffer() { glGenBuffers(1, &id); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer() { glDeleteBuffers(1, &id); }
};

struct VertexArray {
  GLuint id = 0;
  VertexArray() { glGenVertexArrays(1, &id); }
  VertexArray(const VertexArray&) = delete;
  VertexArray& operator=(const VertexArray&) = delete;
  ~VertexArray() { glDeleteVertexArrays(1, &id); }
};

// Vertex layout of a sphere (one point sprite): centre (3), radius, split age, colour coordinate.
constexpr int kSphereFloats = 6;

void sphereAttributes(const VertexArray& vao, const Buffer& vbo) {
  glBindVertexArray(vao.id);
  glBindBuffer(GL_ARRAY_BUFFER, vbo.id);
  const GLsizei stride = kSphereFloats * sizeof(float);
  const int sizes[4] = {3, 1, 1, 1};
  int offset = 0;
  for (GLuint a = 0; a < 4; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<const void*>(std::size_t(offset) * sizeof(float)));
    offset += sizes[a];
  }
  glBindVertexArray(0);
}

void meshAttributes(const VertexArray& vao, const Buffer& vbo, const MeshData& mesh) {
  glBindVertexArray(vao.id);
  glBindBuffer(GL_ARRAY_BUFFER, vbo.id);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * sizeof(float)), mesh.vertices.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(12));
  glBindVertexArray(0);
}

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

// Colour of an opaque collider: skin for driven bodies (the hand), brushed metal for meshes, grey otherwise.
Eigen::Vector3f colliderColor(const sim::ColliderDesc& d) {
  if (d.driven)
    return {0.86f, 0.66f, 0.54f};
  if (d.shape == sim::ShapeType::Mesh)
    return {0.78f, 0.74f, 0.62f};
  return {0.6f, 0.6f, 0.62f};
}

}  // namespace

struct FluidRenderer::Impl {
  ShaderProgram sky, mesh, floor, glass, sphereDepth, sphereThickness, sphereColor, spray, filter, composite,
      overlay;

  VertexArray emptyVao;
  VertexArray particleVao, sprayVao, floorVao, overlayVao;
  Buffer particleVbo, sprayVbo, floorVbo, overlayVbo;
  std::vector<float> staging;
  std::size_t particleCount = 0;
  std::size_t sprayCount = 0;
  float maxRadius = 0.01f;
  float maxPointSize = 64.0f;

  struct Collider {
    VertexArray vao;
    Buffer vbo;
    GLsizei vertices = 0;
    Mat4 model = Mat4::Identity();
    sim::ColliderDesc desc;
  };
  std::vector<std::unique_ptr<Collider>> colliders;

  // floor
  float floorY = 0.0f;
  float floorHalf = 10.0f;
  float floorTile = 0.5f;
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  float sceneSize = 1.0f;

  // legend of the particle view
  ColorField legendField = ColorField::Nu;
  ColorRange legendRange;

  int width = 0, height = 0;
  int halfWidth = 0, halfHeight = 0;  // of the thickness pass
  Texture sceneColor, sceneDepth, fluidDepth[2], thickness, finalColor, finalDepth;
  Framebuffer sceneFbo, depthFbo, filterFbo[2], thicknessFbo, finalFbo;

  explicit Impl(const std::string& dir)
      : sky(dir, "fullscreen.vert", "sky.frag"),
        mesh(dir, "mesh.vert", "mesh.frag"),
        floor(dir, "mesh.vert", "floor.frag"),
        glass(dir, "mesh.vert", "glass.frag"),
        sphereDepth(dir, "sphere.vert", "sphere_depth.frag"),
        sphereThickness(dir, "sphere.vert", "sphere_thickness.frag"),
        sphereColor(dir, "sphere.vert", "sphere_color.frag"),
        spray(dir, "sphere.vert", "spray.frag"),
        filter(dir, "fullscreen.vert", "depth_filter.frag"),
        composite(dir, "fullscreen.vert", "fluid_composite.frag"),
        overlay(dir, "overlay.vert", "overlay.frag") {
    sphereAttributes(particleVao, particleVbo);
    sphereAttributes(sprayVao, sprayVbo);
    glBindVertexArray(overlayVao.id);
    glBindBuffer(GL_ARRAY_BUFFER, overlayVbo.id);
    const GLsizei stride = 7 * sizeof(float);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride, nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(8));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(24));
    glBindVertexArray(0);
    GLfloat range[2] = {1.0f, 64.0f};
    glGetFloatv(GL_POINT_SIZE_RANGE, range);
    maxPointSize = range[1];
    gl::checkError("FluidRenderer setup");
  }

  void resize(int w, int h) {
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
    finalColor.create(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST);
    finalDepth.create(GL_DEPTH_COMPONENT32F, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, GL_NEAREST);
    sceneFbo.build(sceneColor, &sceneDepth, "scene");
    // the depth pass tests against and writes into the scene's depth
    depthFbo.build(fluidDepth[0], &sceneDepth, "fluid depth");
    filterFbo[0].build(fluidDepth[0], nullptr, "filter 0");
    filterFbo[1].build(fluidDepth[1], nullptr, "filter 1");
    // the thickness pass samples the scene's depth instead of testing against it (other size)
    thicknessFbo.build(thickness, nullptr, "thickness");
    finalFbo.build(finalColor, &finalDepth, "final");
  }

  void updateColliders(const std::vector<sim::ColliderState>& states) {
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

  void updateFloor(const FrameData& frame) {
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
      quad.vertices.insert(quad.vertices.end(),
                           {center.x() + xz[0], y, center.z() + xz[1], 0.0f, 1.0f, 0.0f});
    }
    meshAttributes(floorVao, floorVbo, quad);
  }
};

FluidRenderer::FluidRenderer(const std::string& shaderDir) : m_impl(std::make_unique<Impl>(shaderDir)) {}

FluidRenderer::~FluidRenderer() = default;

std::size_t FluidRenderer::particleCount() const {
  return m_impl->particleCount;
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
      o[4] = p.splitTime[i] >= 0.0f ? float(frame.time - double(p.splitTime[i])) : -1.0f;
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
  if (r.maxRadius <= 0.0f)
    r.maxRadius = float(frame.params.particleRadius);
  r.updateColliders(frame.colliders ? *frame.colliders : std::vector<sim::ColliderState>{});
  r.updateFloor(frame);
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

  const Mat4 invView = view.inverse();
  const Eigen::Vector3f eye = invView.block<3, 1>(0, 3);
  const bool fluidView = s.view == RenderSettings::View::Fluid;
  const GLsizei n = GLsizei(r.particleCount);
  glViewport(0, 0, r.width, r.height);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);

  auto viewUniforms = [&](ShaderProgram& p) {
    p.use();
    p.set("uView", view);
    p.set("uProj", projection);
  };
  auto drawMesh = [&](ShaderProgram& p, GLuint vao, GLsizei vertices, const Mat4& model) {
    p.set("uModel", model);
    glBindVertexArray(vao);
    glDrawArrays(GL_TRIANGLES, 0, vertices);
  };
  auto drawGlass = [&](bool backFaces) {
    if (!s.showColliders)
      return;
    viewUniforms(r.glass);
    r.glass.set("uEye", eye);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    glEnable(GL_CULL_FACE);
    glCullFace(backFaces ? GL_FRONT : GL_BACK);
    for (const auto& c : r.colliders) {
      if (!c->desc.container)
        continue;
      r.glass.set("uHalfExtents", Eigen::Vector3f(c->desc.halfExtents.cast<float>()));
      r.glass.set("uEdgeWidth", 0.004f * r.sceneSize);
      drawMesh(r.glass, c->vao.id, c->vertices, c->model);
    }
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  };
  auto drawSpheres = [&](ShaderProgram& p, GLuint vao, GLsizei count, float highlight, int w, int h) {
    viewUniforms(p);
    p.set("uViewport", Eigen::Vector2f(float(w), float(h)));
    p.set("uMaxPointSize", r.maxPointSize);
    p.set("uRadiusScale", 1.0f);
    p.set("uHighlightDuration", highlight);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glBindVertexArray(vao);
    glDrawArrays(GL_POINTS, 0, count);
    glDisable(GL_PROGRAM_POINT_SIZE);
  };

  // 1. scene: sky, floor, opaque colliders and the far walls of the container
  glBindFramebuffer(GL_FRAMEBUFFER, fluidView ? r.sceneFbo.id : r.finalFbo.id);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  r.sky.use();
  r.sky.set("uProj", projection);
  r.sky.set("uInvView", invView);
  glBindVertexArray(r.emptyVao.id);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  if (s.showColliders) {
    viewUniforms(r.floor);
    r.floor.set("uTile", r.floorTile);
    r.floor.set("uCenter", r.center);
    r.floor.set("uFadeRadius", r.floorHalf);
    r.floor.set("uEye", eye);
    drawMesh(r.floor, r.floorVao.id, 6, Mat4::Identity());
    viewUniforms(r.mesh);
    r.mesh.set("uEye", eye);
    for (const auto& c : r.colliders) {
      if (c->desc.container)
        continue;
      r.mesh.set("uColor", colliderColor(c->desc));
      r.mesh.set("uShininess", c->desc.shape == sim::ShapeType::Mesh ? 60.0f : 20.0f);
      drawMesh(r.mesh, c->vao.id, c->vertices, c->model);
    }
  }
  drawGlass(true);
  mark(m_times.scene);

  const float highlight = s.highlightSplits ? s.highlightDuration : 0.0f;
  if (fluidView) {
    // 2. thickness at half resolution: additive, culled by the scene's depth in the shader
    glBindFramebuffer(GL_FRAMEBUFFER, r.thicknessFbo.id);
    glViewport(0, 0, r.halfWidth, r.halfHeight);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    if (n) {
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, r.sceneDepth.id);
      r.sphereThickness.use();
      r.sphereThickness.set("uSceneDepth", 0);
      drawSpheres(r.sphereThickness, r.particleVao.id, n, highlight, r.halfWidth, r.halfHeight);
    }
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
    glViewport(0, 0, r.width, r.height);
    mark(m_times.thickness);

    // 3. depth of the nearest sphere, into the scene's depth so that hidden water is culled
    glBindFramebuffer(GL_FRAMEBUFFER, r.depthFbo.id);
    glClear(GL_COLOR_BUFFER_BIT);
    if (n)
      drawSpheres(r.sphereDepth, r.particleVao.id, n, 0.0f, r.width, r.height);
    mark(m_times.depth);

    // 4. narrow-range filter, horizontal then vertical, ping-ponging between the two depth textures
    glDisable(GL_DEPTH_TEST);
    r.filter.use();
    r.filter.set("uDepth", 0);
    r.filter.set("uPixelsPerMetre", projection(1, 1) * 0.5f * float(r.height));
    r.filter.set("uRadius", s.filterRadius);
    r.filter.set("uMaxPixels", s.filterMaxPixels);
    r.filter.set("uRange", s.filterRange);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(r.emptyVao.id);
    for (int it = 0; it < s.filterIterations; ++it) {
      for (int dir = 0; dir < 2; ++dir) {
        glBindFramebuffer(GL_FRAMEBUFFER, r.filterFbo[1 - dir].id);
        glBindTexture(GL_TEXTURE_2D, r.fluidDepth[dir].id);
        glUniform2i(glGetUniformLocation(r.filter.id(), "uDirection"), dir == 0 ? 1 : 0, dir == 0 ? 0 : 1);
        glDrawArrays(GL_TRIANGLES, 0, 3);
      }
    }
    mark(m_times.filter);

    // 5. shading, into the final image with the water's depth
    glBindFramebuffer(GL_FRAMEBUFFER, r.finalFbo.id);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    r.composite.use();
    r.composite.set("uProj", projection);
    r.composite.set("uInvView", invView);
    r.composite.set("uAbsorption", s.absorption);
    r.composite.set("uRefraction", s.refraction);
    r.composite.set("uHighlightDensity", s.highlightStrength / std::max(r.maxRadius, 1e-6f));
    const GLuint inputs[4] = {r.sceneColor.id, r.sceneDepth.id, r.fluidDepth[0].id, r.thickness.id};
    const char* names[4] = {"uSceneColor", "uSceneDepth", "uFluidDepth", "uThickness"};
    for (int k = 0; k < 4; ++k) {
      glActiveTexture(GLenum(GL_TEXTURE0 + k));
      glBindTexture(GL_TEXTURE_2D, inputs[k]);
      r.composite.set(names[k], k);
    }
    glBindVertexArray(r.emptyVao.id);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glActiveTexture(GL_TEXTURE0);
    glDepthFunc(GL_LESS);
    mark(m_times.composite);
  } else {
    // the particle view: lit spheres straight into the final image
    if (n)
      drawSpheres(r.sphereColor, r.particleVao.id, n, 0.0f, r.width, r.height);
    mark(m_times.composite);
  }

  // 6. spray over the water, the container's near walls, the legend
  if (s.showSpray && r.sprayCount) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    drawSpheres(r.spray, r.sprayVao.id, GLsizei(r.sprayCount), 0.0f, r.width, r.height);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }
  drawGlass(false);
  glDisable(GL_DEPTH_TEST);
  if (!fluidView)
    drawLegend();
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

void FluidRenderer::drawLegend() {
  Impl& r = *m_impl;
  // pixels from the top-left; stb_easy_font glyphs are about 7 px tall, scaled up on large images
  const float scale = std::max(1.0f, std::round(float(r.height) / 360.0f));
  std::vector<float> v;
  auto quad = [&](float x0, float y0, float x1, float y1, const Eigen::Vector4f& c, float t0, float t1) {
    const float pts[6][3] = {{x0, y0, t0}, {x1, y0, t1}, {x1, y1, t1},
                             {x0, y0, t0}, {x1, y1, t1}, {x0, y1, t0}};
    for (const auto& p : pts)
      v.insert(v.end(), {p[0], p[1], c.x(), c.y(), c.z(), c.w(), p[2]});
  };
  auto text = [&](float x, float y, const std::string& s, const Eigen::Vector4f& c) {
    std::vector<float> buffer(s.size() * 16 * 40);  // stb_easy_font: at most ~40 quads a character
    const int quads = stb_easy_font_print(0.0f, 0.0f, const_cast<char*>(s.c_str()), nullptr, buffer.data(),
                                          int(buffer.size() * sizeof(float)));
    const float* q = buffer.data();
    for (int k = 0; k < quads; ++k, q += 16) {  // 4 vertices of x, y, z, rgba8 each
      quad(x + scale * q[0], y + scale * q[1], x + scale * q[8], y + scale * q[9], c, -1.0f, -1.0f);
    }
  };
  auto label = [](float value) {
    char s[32];
    std::snprintf(s, sizeof(s), std::abs(value) < 0.1f && value != 0.0f ? "%.3f" : "%.2g", double(value));
    return std::string(s);
  };
  const char* title = colorFieldLabel(r.legendField);
  const float pad = 8.0f * scale, barH = 12.0f * scale, line = 10.0f * scale;
  const float barW = std::min(std::max(160.0f, float(stb_easy_font_width(const_cast<char*>(title)))) * scale,
                              float(r.width) - 4.0f * pad);
  const float x0 = pad, y0 = float(r.height) - pad - (barH + 2.0f * line + 2.0f * pad);
  const Eigen::Vector4f white(1.0f, 1.0f, 1.0f, 1.0f);
  quad(x0, y0, x0 + barW + 2.0f * pad, float(r.height) - pad, Eigen::Vector4f(0.0f, 0.0f, 0.0f, 0.55f), -1,
       -1);
  text(x0 + pad, y0 + pad, title, white);
  const float barY = y0 + pad + line + 2.0f * scale;
  quad(x0 + pad, barY, x0 + pad + barW, barY + barH, white, 0.0f, 1.0f);
  const std::string lo = label(r.legendRange.lo), hi = label(r.legendRange.hi);
  text(x0 + pad, barY + barH + 3.0f * scale, lo, white);
  text(x0 + pad + barW - float(stb_easy_font_width(const_cast<char*>(hi.c_str()))) * scale,
       barY + barH + 3.0f * scale, hi, white);

  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  r.overlay.use();
  r.overlay.set("uViewport", Eigen::Vector2f(float(r.width), float(r.height)));
  glBindVertexArray(r.overlayVao.id);
  glBindBuffer(GL_ARRAY_BUFFER, r.overlayVbo.id);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(v.size() / 7));
  glDisable(GL_BLEND);
}

}  // namespace fp::render
