#include "render/shader_program.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
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

// Hand-written parsers: std::regex trips GCC 12's maybe-uninitialized warning under the sanitizer build.

// `#include "name"` (spaces allowed around the tokens) -> name; false for any other line
bool parseInclude(const std::string& line, std::string& name) {
  std::size_t k = line.find_first_not_of(" \t");
  if (k == std::string::npos || line[k] != '#')
    return false;
  k = line.find_first_not_of(" \t", k + 1);
  if (k == std::string::npos || line.compare(k, 7, "include") != 0)
    return false;
  k = line.find_first_not_of(" \t", k + 7);
  if (k == std::string::npos || line[k] != '"')
    return false;
  const std::size_t end = line.find('"', k + 1);
  if (end == std::string::npos || line.find_first_not_of(" \t\r", end + 1) != std::string::npos)
    return false;
  name = line.substr(k + 1, end - k - 1);
  return !name.empty();
}

// reads decimal digits at `k`; false when there are none
bool readNumber(const std::string& s, std::size_t& k, long& value) {
  const std::size_t start = k;
  value = 0;
  while (k < s.size() && s[k] >= '0' && s[k] <= '9')
    value = value * 10 + (s[k++] - '0');
  return k > start;
}

// The line number and message of a driver log line: Mesa "0:12(5): msg", NVIDIA "0(12) : msg",
// others "ERROR: 0:12: msg".
bool parseLogLine(const std::string& line, long& number, std::string& message) {
  std::size_t k = line.find_first_not_of(" \t");
  if (k == std::string::npos)
    return false;
  for (const char* prefix : {"ERROR: ", "WARNING: "}) {
    if (line.compare(k, std::strlen(prefix), prefix) == 0)
      k += std::strlen(prefix);
  }
  long source = 0;
  if (!readNumber(line, k, source) || k >= line.size())
    return false;
  if (line[k] == ':') {  // Mesa or generic
    ++k;
    if (!readNumber(line, k, number))
      return false;
    if (k < line.size() && line[k] == '(') {
      long column = 0;
      ++k;
      if (!readNumber(line, k, column) || k >= line.size() || line[k] != ')')
        return false;
      ++k;
    }
  } else if (line[k] == '(') {  // NVIDIA
    ++k;
    if (!readNumber(line, k, number) || k >= line.size() || line[k] != ')')
      return false;
    ++k;
  } else {
    return false;
  }
  k = line.find_first_not_of(" \t", k);
  if (k == std::string::npos || line[k] != ':')
    return false;
  k = line.find_first_not_of(" \t", k + 1);
  message = k == std::string::npos ? std::string() : line.substr(k);
  return true;
}

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
  std::string line, include;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    if (parseInclude(line, include)) {
      const int child = int(out.files.size());
      out.text += "#line " + std::to_string(child * kFileLineStride + 1) + "\n";
      expand(path.parent_path() / include, path.string() + ":" + std::to_string(lineNumber), out, depth + 1);
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
  std::istringstream in(log);
  std::string line, out, message;
  while (std::getline(in, line)) {
    long number = 0;
    if (parseLogLine(line, number, message)) {
      const std::size_t file = std::size_t(number / kFileLineStride);
      const std::string path = file < files.size() ? files[file] : "<file " + std::to_string(file) + ">";
      out += path + ":" + std::to_string(number % kFileLineStride) + ": " + message + "\n";
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
