#include "sim/mesh.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>

namespace fp::sim {

namespace {

/// One-line error naming the file and, when known (> 0), the line.
[[noreturn]] void fail(const std::string& path, std::size_t line, const std::string& what) {
  std::ostringstream s;
  s << path;
  if (line > 0)
    s << ":" << line;
  s << ": " << what;
  std::string msg = s.str();
  // The message is one line even when the offending token or the path carries control characters.
  for (char& c : msg) {
    if (c == '\n' || c == '\r')
      c = ' ';
  }
  throw InputError(msg);
}

/// Splits a line at blanks (spaces and tabs).
std::vector<std::string_view> tokenize(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r'))
      ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r')
      ++j;
    if (j > i)
      tokens.push_back(line.substr(i, j - i));
    i = j;
  }
  return tokens;
}

/// Parses a whole token as a finite double. from_chars is locale independent, unlike strtod and streams.
bool parseDouble(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+')
    token.remove_prefix(1);
  if (token.empty())
    return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end && std::isfinite(value);
}

/// Parses a whole token as a signed integer.
bool parseInt(std::string_view token, long long& value) {
  if (!token.empty() && token.front() == '+')
    token.remove_prefix(1);
  if (token.empty())
    return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

/// A face corner before validation: the 0-based vertex index it resolves to, and where it was read.
struct PendingFace {
  std::vector<long long> corners;
  std::size_t line = 0;
};

}  // namespace

TriangleMesh TriangleMesh::loadObj(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    fail(path, 0, "cannot open mesh file");

  TriangleMesh mesh;
  std::vector<PendingFace> faces;
  std::string line;
  std::size_t lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    const std::vector<std::string_view> tok = tokenize(line);
    if (tok.empty() || tok[0].front() == '#')
      continue;
    if (tok[0] == "v") {
      // "v x y z [w]": the optional weight (rational curves) is irrelevant to a polygon mesh.
      if (tok.size() < 4 || tok.size() > 5)
        fail(path, lineNo, "vertex needs 3 coordinates");
      double c[3];
      for (int k = 0; k < 3; ++k) {
        if (!parseDouble(tok[k + 1], c[k])) {
          fail(path, lineNo, "malformed number '" + std::string(tok[k + 1]) + "'");
        }
      }
      if (tok.size() == 5) {
        double w;
        if (!parseDouble(tok[4], w))
          fail(path, lineNo, "malformed number '" + std::string(tok[4]) + "'");
      }
      mesh.vertices.emplace_back(c[0], c[1], c[2]);
    } else if (tok[0] == "f") {
      if (tok.size() < 4)
        fail(path, lineNo, "face needs at least 3 vertices");
      PendingFace face;
      face.line = lineNo;
      for (std::size_t k = 1; k < tok.size(); ++k) {
        // Only the position index (before the first '/') matters; texture and normal indices are ignored.
        const std::string_view entry = tok[k];
        const std::string_view index = entry.substr(0, entry.find('/'));
        long long i = 0;
        if (!parseInt(index, i))
          fail(path, lineNo, "malformed face index '" + std::string(entry) + "'");
        if (i == 0)
          fail(path, lineNo, "face index 0 is invalid (indices start at 1)");
        // Negative indices count back from the last vertex read so far.
        const long long n = static_cast<long long>(mesh.vertices.size());
        face.corners.push_back(i > 0 ? i - 1 : n + i);
      }
      faces.push_back(std::move(face));
    }
    // vn, vt, o, g, s, usemtl, mtllib and anything else do not change the geometry.
  }
  if (in.bad())
    fail(path, lineNo, "read error");

  // Positive indices are checked once the whole file is read, so faces may reference vertices listed later.
  const long long n = static_cast<long long>(mesh.vertices.size());
  if (n > static_cast<long long>(std::numeric_limits<std::uint32_t>::max()))
    fail(path, 0, "too many vertices");
  for (const PendingFace& f : faces) {
    for (long long c : f.corners) {
      if (c < 0 || c >= n) {
        fail(path, f.line, "face index out of range (" + std::to_string(n) + " vertices)");
      }
    }
    // Polygons are fanned around their first corner (exact for the convex polygons OBJ exporters write).
    for (std::size_t k = 1; k + 1 < f.corners.size(); ++k) {
      mesh.triangles.push_back({static_cast<std::uint32_t>(f.corners[0]),
                                static_cast<std::uint32_t>(f.corners[k]),
                                static_cast<std::uint32_t>(f.corners[k + 1])});
    }
  }
  if (mesh.triangles.empty())
    fail(path, 0, "mesh has no triangles");
  return mesh;
}

void TriangleMesh::saveObj(const std::string& path) const {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr)
    fail(path, 0, "cannot open mesh file for writing");
  bool ok = std::fprintf(f, "# FluidPlaying mesh: %zu vertices, %zu triangles\n", vertices.size(),
                         triangles.size()) > 0;
  // 17 significant digits make the text round trip bit-exact.
  for (const Vec3d& v : vertices) {
    ok = ok && std::fprintf(f, "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z()) > 0;
  }
  for (const auto& t : triangles) {
    ok = ok && std::fprintf(f, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1) > 0;
  }
  ok = (std::fclose(f) == 0) && ok;
  if (!ok)
    fail(path, 0, "cannot write mesh file");
}

Aabb TriangleMesh::bounds() const {
  Aabb box;  // empty
  for (const Vec3d& v : vertices)
    box.extend(v);
  return box;
}

void TriangleMesh::scale(double s) {
  for (Vec3d& v : vertices)
    v *= s;
}

double TriangleMesh::area() const {
  double sum = 0.0;
  for (const auto& t : triangles) {
    const Vec3d& a = vertices[t[0]];
    sum += 0.5 * (vertices[t[1]] - a).cross(vertices[t[2]] - a).norm();
  }
  return sum;
}

}  // namespace fp::sim
