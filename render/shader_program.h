#pragma once
/// GLSL programs built from files in the shader directory. A file may pull in another with
/// `#include "name.glsl"`; compile errors are reported as `path:line: message` for the file that holds the
/// line.

#include <Eigen/Core>
#include <string>
#include <unordered_map>
#include <vector>

namespace fp::render {

/// The shader directory: `shaders/` under the working directory if it has the renderer's files, else the
/// source tree's.
std::string defaultShaderDir();

/// A shader's text with includes expanded; the lines of files[k] are numbered from k * 100000 + 1.
struct ShaderSource {
  std::string text;                ///< ready for glShaderSource
  std::vector<std::string> files;  ///< the main file, then each included file
};

/// Reads `dir/name` and expands its includes. Throws ShaderError naming the file when one is missing.
ShaderSource loadShaderSource(const std::string& dir, const std::string& name);

/// Rewrites a driver's info log (Mesa `0:12(5): error`, NVIDIA `0(12) : error`) as `path:12: error` lines,
/// `files` being the ShaderSource's.
std::string formatShaderLog(const std::string& log, const std::vector<std::string>& files);

/// A linked vertex + fragment program with cached uniform locations.
class ShaderProgram {
 public:
  ShaderProgram() = default;
  /// Compiles and links `dir/vertex` and `dir/fragment`; throws ShaderError with the file and line of the
  /// first errors. A GL context must be current.
  ShaderProgram(const std::string& dir, const std::string& vertex, const std::string& fragment);
  ~ShaderProgram();
  ShaderProgram(ShaderProgram&& other) noexcept;
  ShaderProgram& operator=(ShaderProgram&& other) noexcept;
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  /// binds the program
  void use() const;
  /// the GL name of the program
  unsigned id() const { return m_id; }

  /// Uniform setters; a uniform the compiler removed is ignored.
  void set(const char* name, int value);
  void set(const char* name, float value);
  void set(const char* name, const Eigen::Vector2f& value);
  void set(const char* name, const Eigen::Vector3f& value);
  void set(const char* name, const Eigen::Vector4f& value);
  void set(const char* name, const Eigen::Matrix4f& value);

 private:
  int location(const char* name);
  unsigned m_id = 0;
  std::unordered_map<std::string, int> m_locations;
};

}  // namespace fp::render
