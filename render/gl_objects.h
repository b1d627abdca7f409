#pragma once
/// Owners of OpenGL names (textures, framebuffers, buffers, vertex arrays) and the vertex layouts of the
/// renderer's spheres and meshes. The GL context that created an object must be current when it dies.

#include <cstddef>

#include "render/collider_mesh.h"
#include "render/gl_api.h"

namespace fp::render {

/// A 2D texture, (re)allocated by create().
struct Texture {
  GLuint id = 0;  ///< GL name, 0 until create()
  Texture() = default;
  Texture(const Texture&) = delete;
  Texture& operator=(const Texture&) = delete;
  ~Texture();
  /// (re)allocates width x height texels [px] of `internalFormat`, clamped at the edges, with `filter`
  void create(GLint internalFormat, int width, int height, GLenum format, GLenum type, GLint filter);
};

/// A framebuffer of one colour texture and an optional depth texture.
struct Framebuffer {
  GLuint id = 0;  ///< GL name, 0 until build()
  Framebuffer() = default;
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;
  ~Framebuffer();
  /// (re)builds it from `color` and `depth` (may be null); throws RenderError naming `name` when incomplete
  void build(const Texture& color, const Texture* depth, const char* name);
};

/// A buffer object.
struct Buffer {
  GLuint id = 0;  ///< GL name
  Buffer();
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer();
};

/// A vertex array object.
struct VertexArray {
  GLuint id = 0;  ///< GL name
  VertexArray();
  VertexArray(const VertexArray&) = delete;
  VertexArray& operator=(const VertexArray&) = delete;
  ~VertexArray();
};

/// Floats of one sphere (one point sprite): centre (3), radius, split age, colour coordinate.
constexpr int kSphereFloats = 6;

/// Binds the sphere layout of `vbo` to `vao` (attributes 0..3 of shaders/sphere.vert).
void sphereAttributes(const VertexArray& vao, const Buffer& vbo);
/// Uploads `mesh` into `vbo` and binds its position and normal to `vao` (shaders/mesh.vert).
void meshAttributes(const VertexArray& vao, const Buffer& vbo, const MeshData& mesh);
/// Binds the overlay layout (pixel xy, rgba, colour-map coordinate; shaders/overlay.vert) of `vbo` to `vao`.
void overlayAttributes(const VertexArray& vao, const Buffer& vbo);

}  // namespace fp::render
