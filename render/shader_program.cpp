#include "render/shader_program.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "render/gl_api.h"
#include "render/render_error.h"

namespace fp::render {

namespace fs = std::filesystem;

std::string defaultShaderDir() {
  // The probe file is one every renderer build needs; a stray shaders/ folder of another project is skipped.
  if (fs::exists("shaders/fluid_composite.frag"))
    return "shaders";
  return std::string(FP_RENDER_SOURCE_DIR) + "/shaders";
}

namespace {

constexpr int kFileLineStride = 100000;

std::string readFile(const fs::path& path, const std::string& includedFrom) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw ShaderError("shader file not found: " + path.string() +
                      (includedFrom.empty() ? "" : " (included from " + includedFrom + ")"));
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Appends `path` to `out` with its includes expanded. `#line` directives keep the driver's line numbers
// pointing into the right file: file k's lines are numbered from k * kFileLineStride, because drivers differ
// in reporting the source-string number (Mesa always says 0). GLSL 3.30 numbers the line after `#line N` as
// N.
void expand(const fs::path& path, const std::string& includedFrom, ShaderSource& out, int depth) {
  if (depth > 8)
    throw ShaderError(path.string() + ": includes nested too deeply");
  const int fileIndex = int(out.files.size());
  out.files.push_back(path.string());
  std::istringstream in(readFile(path, includedFrom));
  static const std::regex includeLine(R"(^\s*#\s*include\s+"([^"]+)\"\s*$)");
  std::string line;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    std::smatch match;
    if (std::regex_match(line, match, includeLine)) {
      const int child = int(out.files.size());
      out.text += "#line " + std::to_string(child * kFileLineStride + 1) + "\n";
      expand(path.parent_path() / match[1].str(), path.string() + ":" + std::to_string(lineNumber), out,
             depth + 1);
      out.text += "#line " + std::to_string(fileIndex * kFileLineStride + lineNumber + 1) + "\n";
    } else {
      out.text += line + "\n";
    }
  }
}

std::string shaderLog(GLuint shader) {
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(std::size_t(std::max(length, 1)), '\0');
  glGetShaderInfoLog(shader, length, nullptr, log.data());
  log.resize(std::strlen(log.c_str()));
  return log;
}

GLuint compile(GLenum type, const std::string& dir, const std::string& name) {
  const ShaderSource source = loadShaderSource(dir, name);
  const GLuint shader = glCreateShader(type);
  const char* text = source.text.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = formatShaderLog(shaderLog(shader), source.files);
    glDeleteShader(shader);
    throw ShaderError("shader " + source.files.front() + " does not compile:\n" + log);
  }
  return shader;
}

}  // namespace

ShaderSource loadShaderSource(const std::string& dir, const std::string& name) {
  ShaderSource source;
  expand(fs::path(dir) / name, "", source, 0);
  return source;
}

std::string formatShaderLog(const std::string& log, const std::vector<std::string>& files) {
  // Mesa "0:12(5): error: ...", NVIDIA "0(12) : error C1008: ...", others "ERROR: 0:12: ..."
  static const std::regex mesa(R"(^\s*(\d+):(\d+)\(\d+\):\s*(.*)$)");
  static const std::regex nvidia(R"(^\s*(\d+)\((\d+)\)\s*:\s*(.*)$)");
  static const std::regex generic(R"(^\s*(?:ERROR|WARNING):\s*(\d+):(\d+):\s*(.*)$)");
  std::istringstream in(log);
  std::string line, out;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_match(line, m, mesa) || std::regex_match(line, m, nvidia) ||
        std::regex_match(line, m, generic)) {
      const long number = std::stol(m[2].str());
      const std::size_t file = std::size_t(number / kFileLineStride);
      const std::string path = file < files.size() ? files[file] : "<file " + std::to_string(file) + ">";
      out += path + ":" + std::to_string(number % kFileLineStride) + ": " + m[3].str() + "\n";
    } else if (!line.empty()) {
      out += line + "\n";
    }
  }
  if (!out.empty() && out.back() == '\n')
    out.pop_back();
  return out;
}

ShaderProgram::ShaderProgram(const std::string& dir, const std::string& vertex, const std::string& fragment) {
  const GLuint vs = compile(GL_VERTEX_SHADER, dir, vertex);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, dir, fragment);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  m_id = glCreateProgram();
  glAttachShader(m_id, vs);
  glAttachShader(m_id, fs);
  glLinkProgram(m_id);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(m_id, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(m_id, GL_INFO_LOG_LENGTH, &length);
    std::string log(std::size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(m_id, length, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    glDeleteProgram(m_id);
    m_id = 0;
    throw ShaderError("shaders " + (fs::path(dir) / vertex).string() + " + " +
                      (fs::path(dir) / fragment).string() + " do not link: " + log);
  }
}

ShaderProgram::~ShaderProgram() {
  if (m_id)
    glDeleteProgram(m_id);
}

ShaderProgram::ShaderProgram(ShaderProgram&& other) noexcept
    : m_id(other.m_id), m_locations(std::move(other.m_locations)) {
  other.m_id = 0;
}

ShaderProgram& ShaderProgram::operator=(ShaderProgram&& other) noexcept {
  if (this != &other) {
    if (m_id)
      glDeleteProgram(m_id);
    m_id = other.m_id;
    m_locations = std::move(other.m_locations);
    other.m_id = 0;
  }
  return *this;
}

void ShaderProgram::use() const {
  glUseProgram(m_id);
}

int ShaderProgram::location(const char* name) {
  auto it = m_locations.find(name);
  if (it == m_locations.end())
    it = m_locations.emplace(name, glGetUniformLocation(m_id, name)).first;
  return it->second;
}

void ShaderProgram::set(const char* name, int value) {
  glUniform1i(location(name), value);
}
void ShaderProgram::set(const char* name, float value) {
  glUniform1f(location(name), value);
}
void ShaderProgram::set(const char* name, const Eigen::Vector2f& value) {
  glUniform2fv(location(name), 1, value.data());
}
void ShaderProgram::set(const char* name, const Eigen::Vector3f& value) {
  glUniform3fv(location(name), 1, value.data());
}
void ShaderProgram::set(const char* name, const Eigen::Vector4f& value) {
  glUniform4fv(location(name), 1, value.data());
}
void ShaderProgram::set(const char* name, const Eigen::Matrix4f& value) {
  glUniformMatrix4fv(location(name), 1, GL_FALSE, value.data());
}

}  // namespace fp::render
