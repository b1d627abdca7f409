#include "render/offscreen_context.h"

#include <vector>

#include "render/gl_api.h"
#include "render/render_error.h"

// glew.h undefines GLAPI at its end, and osmesa.h needs it.
#ifndef GLAPI
#define GLAPI extern
#endif
#include <GL/osmesa.h>

namespace fp::render {

struct OffscreenContext::Impl {
  OSMesaContext context = nullptr;
  std::vector<unsigned char> buffer;
  int width = 0;
  int height = 0;
};

namespace {

OSMesaContext createCoreContext(int major, int minor) {
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            24,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            major,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            minor,
                            0};
  return OSMesaCreateContextAttribs(attributes, nullptr);
}

gl::Proc osmesaProc(const char* name) {
  return reinterpret_cast<gl::Proc>(OSMesaGetProcAddress(name));
}

}  // namespace

OffscreenContext::OffscreenContext(int width, int height) : m_impl(std::make_unique<Impl>()) {
  if (width <= 0 || height <= 0)
    throw RenderError("offscreen context: size must be positive");
  m_impl->context = createCoreContext(4, 5);
  if (!m_impl->context)
    m_impl->context = createCoreContext(3, 3);
  if (!m_impl->context)
    throw RenderError("cannot create an OSMesa OpenGL 3.3 core context (is libosmesa6 installed?)");
  m_impl->width = width;
  m_impl->height = height;
  m_impl->buffer.assign(std::size_t(width) * std::size_t(height) * 4, 0);
  makeCurrent();
  gl::loadFunctions(&osmesaProc);
  m_description = "OSMesa, " + gl::versionString();
}

OffscreenContext::~OffscreenContext() {
  if (m_impl && m_impl->context)
    OSMesaDestroyContext(m_impl->context);
}

void OffscreenContext::makeCurrent() {
  if (!OSMesaMakeCurrent(m_impl->context, m_impl->buffer.data(), GL_UNSIGNED_BYTE, m_impl->width,
                         m_impl->height)) {
    throw RenderError("OSMesaMakeCurrent failed");
  }
}

}  // namespace fp::render
