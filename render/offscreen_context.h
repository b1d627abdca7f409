#pragma once
/// An OpenGL context with no window and no display: OSMesa (Mesa's software rasteriser, llvmpipe). The
/// headless mode and the image tests render through it with DISPLAY unset; the renderer draws into its own
/// framebuffers, so the context's buffer only has to exist.

#include <memory>
#include <string>

namespace fp::render {

/// An offscreen GL context, current on the creating thread.
class OffscreenContext {
 public:
  /// Creates an OSMesa context (4.5 core, else 3.3 core), makes it current with a width x height buffer and
  /// loads every GL function. Throws RenderError when no such context can be made.
  OffscreenContext(int width, int height);
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  /// makes this context current on the calling thread
  void makeCurrent();
  /// "OSMesa, 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& description() const { return m_description; }

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  std::string m_description;
};

}  // namespace fp::render
