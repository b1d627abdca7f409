#pragma once
/// The inside of FluidRenderer (render/fluid_renderer.h), shared by its files: the GL objects and uploaded
/// frame (fluid_renderer.cpp) and one function a pass (fluid_passes.cpp). Not for other users.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "render/fluid_renderer.h"
#include "render/gl_objects.h"
#include "render/shader_program.h"

namespace fp::render {

/// What every pass of one renderView reads.
struct ViewParams {
  Mat4 view;            ///< world to view
  Mat4 projection;      ///< view to clip
  Mat4 invView;         ///< view to world
  Eigen::Vector3f eye;  ///< camera position, world [m]
  const RenderSettings* settings = nullptr;
  float highlight = 0.0f;  ///< split highlight duration [s], 0: off
};

struct FluidRenderer::Impl {
  ShaderProgram sky, mesh, floor, glass, sphereDepth, sphereWet, sphereThickness, sphereColor, spray, filter,
      depthDown, depthUp, composite, overlay;

  VertexArray emptyVao;
  VertexArray particleVao, sprayVao, floorVao, overlayVao, wetVao;
  Buffer particleVbo, sprayVbo, floorVbo, overlayVbo, wetIndices;
  std::vector<float> staging;
  std::vector<std::uint32_t> wetStaging;
  std::size_t particleCount = 0;
  std::size_t wetCount = 0;  // particles next to the glass of the container (wetVao's indices)
  std::array<std::pair<std::size_t, std::size_t>, 4> wetFaces{};  // first index and count a side
  std::size_t sprayCount = 0;
  float maxRadius = 0.01f;   // largest draw radius of the frame [m]
  float fineRadius = 0.01f;  // the finest particle radius of the frame [m]
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
  Texture halfDepth[2];  // the half-resolution filter's ping-pong: depth, radius, thickness (RGBA)
  Framebuffer sceneFbo, depthFbo, filterFbo[2], halfFbo[2], thicknessFbo, finalFbo;
  int surface = 0;                 // which of fluidDepth holds the filtered surface of the last view
  bool smoothedThickness = false;  // the thickness of the last view is in halfDepth[0].ba, else in thickness

  explicit Impl(const std::string& dir);
  void resize(int w, int h);
  void updateColliders(const std::vector<sim::ColliderState>& states);
  void updateFloor(const FrameData& frame);
  /// lists the particles within `reach` radii of each side (x and z faces) of the container
  void updateWet(const FrameData& frame, float reach);
  /// the first container collider, or null
  const Collider* container() const;

  // The passes of renderView, in order (fluid_passes.cpp).
  /// 1. sky, floor, opaque colliders and the far walls of the container, into `framebuffer`
  void drawScene(const ViewParams& v, GLuint framebuffer);
  /// 2. additive thickness at half resolution
  void drawThickness(const ViewParams& v);
  /// 3. depth of the nearest sphere (the glass where water wets it)
  void drawDepth(const ViewParams& v);
  /// 4. the depth filter, at half resolution (reduced, filtered, interpolated back) or at full resolution,
  /// ping-ponging between two depth textures; the result is in fluidDepth[surface]
  void filterDepth(const ViewParams& v);
  /// 5. shading of the water into the final image
  void drawComposite(const ViewParams& v);
  /// 5'. the particle view: lit spheres coloured by the inspected field, spray in green
  void drawParticleView(const ViewParams& v);
  /// 6. spray over the water (fluid view), the container's near walls
  void drawOverlay(const ViewParams& v);
  /// the legend of the particle view over the final image
  void drawLegend();

  // helpers of the passes
  void drawGlass(const ViewParams& v, bool backFaces);
  void drawSpheres(const ViewParams& v, ShaderProgram& p, GLuint vao, GLsizei count, float highlight, int w,
                   int h, float spriteScale = 1.0f);
};

}  // namespace fp::render
