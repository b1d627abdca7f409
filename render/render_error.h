#pragma once
/// Errors of the renderer. Each message is one line that names the file, shader or GL call at fault.

#include <stdexcept>
#include <string>

namespace fp::render {

/// no usable GL context, a GL error, an image that cannot be written
class RenderError : public std::runtime_error {
 public:
  explicit RenderError(const std::string& what) : std::runtime_error(what) {}
};

/// a shader file that is missing or does not compile or link; the message names the file and line
class ShaderError : public RenderError {
 public:
  explicit ShaderError(const std::string& what) : RenderError(what) {}
};

}  // namespace fp::render
