// The passes of FluidRenderer::renderView, one function each (see docs/rendering.md for the table).
#include <algorithm>

#include "render/fluid_renderer_impl.h"
#include "render/legend.h"

namespace fp::render {

namespace {

void viewUniforms(ShaderProgram& p, const ViewParams& v) {
  p.use();
  p.set("uView", v.view);
  p.set("uProj", v.projection);
}

void drawMesh(ShaderProgram& p, GLuint vao, GLsizei vertices, const Mat4& model) {
  p.set("uModel", model);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, vertices);
}

// Colour of an opaque collider: skin for driven bodies (the hand), brushed metal for meshes, grey otherwise.
Eigen::Vector3f colliderColor(const sim::ColliderDesc& d) {
  if (d.driven)
    return {0.86f, 0.66f, 0.54f};
  if (d.shape == sim::ShapeType::Mesh)
    return {0.78f, 0.74f, 0.62f};
  return {0.6f, 0.6f, 0.62f};
}

// the debug colour of spray in the particle view
const Eigen::Vector4f kSprayDebugColor(0.1f, 0.85f, 0.2f, 1.0f);

}  // namespace

void FluidRenderer::Impl::drawGlass(const ViewParams& v, bool backFaces) {
  if (!v.settings->showColliders)
    return;
  viewUniforms(glass, v);
  glass.set("uEye", v.eye);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glDepthMask(GL_FALSE);
  glEnable(GL_CULL_FACE);
  glCullFace(backFaces ? GL_FRONT : GL_BACK);
  if (!backFaces) {
    // the near glass wins over water lying on it (the wetted glass puts the surface on the glass plane):
    // without the offset the two depths tie and the glass's tint speckles pixel by pixel
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(-1.0f, -4.0f);
  }
  for (const auto& c : colliders) {
    if (!c->desc.container)
      continue;
    glass.set("uHalfExtents", Eigen::Vector3f(c->desc.halfExtents.cast<float>()));
    glass.set("uEdgeWidth", 0.004f * sceneSize);
    drawMesh(glass, c->vao.id, c->vertices, c->model);
  }
  glDisable(GL_POLYGON_OFFSET_FILL);
  glDisable(GL_CULL_FACE);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}

void FluidRenderer::Impl::drawSpheres(const ViewParams& v, ShaderProgram& p, GLuint vao, GLsizei count,
                                      float highlight, int w, int h, float spriteScale) {
  viewUniforms(p, v);
  p.set("uViewport", Eigen::Vector2f(float(w), float(h)));
  p.set("uMaxPointSize", maxPointSize);
  p.set("uSpriteScale", spriteScale);
  p.set("uHighlightDuration", highlight);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glBindVertexArray(vao);
  glDrawArrays(GL_POINTS, 0, count);
  glDisable(GL_PROGRAM_POINT_SIZE);
}

void FluidRenderer::Impl::drawScene(const ViewParams& v, GLuint framebuffer) {
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  sky.use();
  sky.set("uProj", v.projection);
  sky.set("uInvView", v.invView);
  glBindVertexArray(emptyVao.id);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  if (v.settings->showColliders) {
    viewUniforms(floor, v);
    floor.set("uTile", floorTile);
    floor.set("uCenter", center);
    floor.set("uFadeRadius", floorHalf);
    floor.set("uEye", v.eye);
    drawMesh(floor, floorVao.id, 6, Mat4::Identity());
    viewUniforms(mesh, v);
    mesh.set("uEye", v.eye);
    for (const auto& c : colliders) {
      if (c->desc.container)
        continue;
      mesh.set("uColor", colliderColor(c->desc));
      mesh.set("uShininess", c->desc.shape == sim::ShapeType::Mesh ? 60.0f : 20.0f);
      drawMesh(mesh, c->vao.id, c->vertices, c->model);
    }
  }
  drawGlass(v, true);
}

void FluidRenderer::Impl::drawThickness(const ViewParams& v) {
  glBindFramebuffer(GL_FRAMEBUFFER, thicknessFbo.id);
  glViewport(0, 0, halfWidth, halfHeight);
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  if (particleCount) {
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, sceneDepth.id);
    sphereThickness.use();
    sphereThickness.set("uSceneDepth", 0);
    drawSpheres(v, sphereThickness, particleVao.id, GLsizei(particleCount), v.highlight, halfWidth,
                halfHeight);
  }
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glViewport(0, 0, width, height);
}

void FluidRenderer::Impl::drawDepth(const ViewParams& v) {
  const RenderSettings& s = *v.settings;
  glBindFramebuffer(GL_FRAMEBUFFER, depthFbo.id);
  glClear(GL_COLOR_BUFFER_BIT);
  if (!particleCount)
    return;
  drawSpheres(v, sphereDepth, particleVao.id, GLsizei(particleCount), 0.0f, width, height);
  const Collider* box = container();
  if (box && wetCount) {
    // the glass wetted by the spheres next to it (listed by update()), nearer than those spheres
    sphereWet.use();
    sphereWet.set("uViewToContainer", Mat4(box->model.inverse() * v.invView));
    sphereWet.set("uContainerHalf", Eigen::Vector3f(box->desc.halfExtents.cast<float>()));
    sphereWet.set("uWetReach", s.wetReach);
    // sprites 1.5 times larger: the disc of glass a sphere wets is that wide
    viewUniforms(sphereWet, v);
    sphereWet.set("uViewport", Eigen::Vector2f(float(width), float(height)));
    sphereWet.set("uMaxPointSize", maxPointSize);
    sphereWet.set("uSpriteScale", 1.5f);
    sphereWet.set("uHighlightDuration", 0.0f);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glBindVertexArray(wetVao.id);
    // the sides whose outside faces the eye: -x, +x, -z, +z
    const Eigen::Vector3f eye = (box->model.inverse() * v.eye.homogeneous()).head<3>();
    const Eigen::Vector3f half = box->desc.halfExtents.cast<float>();
    const bool facing[4] = {eye.x() < -half.x(), eye.x() > half.x(), eye.z() < -half.z(), eye.z() > half.z()};
    for (int f = 0; f < 4; ++f) {
      const auto [first, count] = wetFaces[std::size_t(f)];
      if (facing[f] && count)
        glDrawElements(GL_POINTS, GLsizei(count), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(first * sizeof(std::uint32_t)));
    }
    glDisable(GL_PROGRAM_POINT_SIZE);
  }
}

void FluidRenderer::Impl::filterDepth(const ViewParams& v) {
  const RenderSettings& s = *v.settings;
  surface = 0;
  smoothedThickness = false;
  if (s.filterIterations <= 0)
    return;
  const bool half = s.filterHalfResolution;
  const float scale = half ? 0.5f : 1.0f;
  glDisable(GL_DEPTH_TEST);
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(emptyVao.id);
  Framebuffer* fbo = filterFbo;
  Texture* tex = fluidDepth;
  if (half) {
    // the sphere depth reduced to half resolution
    glViewport(0, 0, halfWidth, halfHeight);
    depthDown.use();
    depthDown.set("uDepth", 0);
    depthDown.set("uRange", s.filterRange);
    depthDown.set("uFineRadius", fineRadius);
    depthDown.set("uThickness", 1);
    glBindFramebuffer(GL_FRAMEBUFFER, halfFbo[0].id);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, thickness.id);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, fluidDepth[0].id);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    fbo = halfFbo;
    tex = halfDepth;
  }
  filter.use();
  filter.set("uDepth", 0);
  filter.set("uPixelsPerMetre", scale * v.projection(1, 1) * 0.5f * float(height));
  filter.set("uRadius", s.filterRadius);
  filter.set("uFineRadius", fineRadius);
  filter.set("uMaxTaps", s.filterMaxTaps);
  filter.set("uMaxPixels", scale * s.filterMaxPixels);
  filter.set("uRange", s.filterRange);
  filter.set("uThicknessBlur", half ? s.thicknessBlur : 0.0f);
  const GLint direction = glGetUniformLocation(filter.id(), "uDirection");
  for (int it = 0; it < s.filterIterations; ++it) {
    for (int dir = 0; dir < 2; ++dir) {
      glBindFramebuffer(GL_FRAMEBUFFER, fbo[1 - dir].id);
      glBindTexture(GL_TEXTURE_2D, tex[dir].id);
      glUniform2i(direction, dir == 0 ? 1 : 0, dir == 0 ? 0 : 1);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  }
  if (half) {
    // back to full resolution inside the full-resolution outline, into fluidDepth[1]
    glViewport(0, 0, width, height);
    depthUp.use();
    depthUp.set("uDepth", 0);
    depthUp.set("uFiltered", 1);
    depthUp.set("uRange", s.filterRange);
    depthUp.set("uFineRadius", fineRadius);
    // a pixel 4 fine radii behind the filtered surface around it looks through a gap between its spheres
    depthUp.set("uHoleDepth", s.fillHoles ? 4.0f : 0.0f);
    glBindFramebuffer(GL_FRAMEBUFFER, filterFbo[1].id);
    glBindTexture(GL_TEXTURE_2D, fluidDepth[0].id);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, halfDepth[0].id);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glActiveTexture(GL_TEXTURE0);
    surface = 1;
    smoothedThickness = s.thicknessBlur > 0.0f;
  }
}

void FluidRenderer::Impl::drawComposite(const ViewParams& v) {
  const RenderSettings& s = *v.settings;
  glBindFramebuffer(GL_FRAMEBUFFER, finalFbo.id);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_ALWAYS);
  composite.use();
  composite.set("uProj", v.projection);
  composite.set("uInvView", v.invView);
  composite.set("uAbsorption", s.absorption);
  composite.set("uRefraction", s.refraction);
  composite.set("uFineRadius", fineRadius);
  composite.set("uHighlightDensity", s.highlightStrength / std::max(maxRadius, 1e-6f));
  composite.set("uThicknessInBA", int(smoothedThickness));
  const GLuint inputs[4] = {sceneColor.id, sceneDepth.id, fluidDepth[surface].id,
                            smoothedThickness ? halfDepth[0].id : thickness.id};
  const char* names[4] = {"uSceneColor", "uSceneDepth", "uFluidDepth", "uThickness"};
  for (int k = 0; k < 4; ++k) {
    glActiveTexture(GLenum(GL_TEXTURE0 + k));
    glBindTexture(GL_TEXTURE_2D, inputs[k]);
    composite.set(names[k], k);
  }
  glBindVertexArray(emptyVao.id);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glActiveTexture(GL_TEXTURE0);
  glDepthFunc(GL_LESS);
}

void FluidRenderer::Impl::drawParticleView(const ViewParams& v) {
  sphereColor.use();
  sphereColor.set("uFlatColor", Eigen::Vector4f(0, 0, 0, 0));
  if (particleCount)
    drawSpheres(v, sphereColor, particleVao.id, GLsizei(particleCount), 0.0f, width, height);
  if (v.settings->showSpray && sprayCount) {
    sphereColor.use();
    sphereColor.set("uFlatColor", kSprayDebugColor);
    drawSpheres(v, sphereColor, sprayVao.id, GLsizei(sprayCount), 0.0f, width, height);
  }
}

void FluidRenderer::Impl::drawOverlay(const ViewParams& v) {
  const bool fluidView = v.settings->view == RenderSettings::View::Fluid;
  if (fluidView && v.settings->showSpray && sprayCount) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, fluidDepth[surface].id);
    spray.use();
    spray.set("uFluidDepth", 0);
    spray.set("uInvView", v.invView);
    spray.set("uFoamDepth", 3.0f * fineRadius);
    drawSpheres(v, spray, sprayVao.id, GLsizei(sprayCount), 0.0f, width, height);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }
  drawGlass(v, false);
}

void FluidRenderer::Impl::drawLegend() {
  const std::vector<float> v = legendVertices(legendField, legendRange, width, height);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  overlay.use();
  overlay.set("uViewport", Eigen::Vector2f(float(width), float(height)));
  glBindVertexArray(overlayVao.id);
  glBindBuffer(GL_ARRAY_BUFFER, overlayVbo.id);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(v.size() / 7));
  glDisable(GL_BLEND);
}

}  // namespace fp::render
