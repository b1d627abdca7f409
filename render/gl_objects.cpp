#include "render/gl_objects.h"

#include <cstdio>
#include <string>

#include "render/render_error.h"

namespace fp::render {

Texture::~Texture() {
  if (id)
    glDeleteTextures(1, &id);
}

void Texture::create(GLint internalFormat, int width, int height, GLenum format, GLenum type, GLint filter) {
  if (!id)
    glGenTextures(1, &id);
  glBindTexture(GL_TEXTURE_2D, id);
  glTexImage2D(GL_TEXTURE_2D, 0, internalFormat, width, height, 0, format, type, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

Framebuffer::~Framebuffer() {
  if (id)
    glDeleteFramebuffers(1, &id);
}

void Framebuffer::build(const Texture& color, const Texture* depth, const char* name) {
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

Buffer::Buffer() {
  glGenBuffers(1, &id);
}

Buffer::~Buffer() {
  glDeleteBuffers(1, &id);
}

VertexArray::VertexArray() {
  glGenVertexArrays(1, &id);
}

VertexArray::~VertexArray() {
  glDeleteVertexArrays(1, &id);
}

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

void overlayAttributes(const VertexArray& vao, const Buffer& vbo) {
  glBindVertexArray(vao.id);
  glBindBuffer(GL_ARRAY_BUFFER, vbo.id);
  const GLsizei stride = 7 * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(8));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(24));
  glBindVertexArray(0);
}

}  // namespace fp::render
