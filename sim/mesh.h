#pragma once
/// Triangle meshes loaded from Wavefront OBJ, for colliders (the propeller, the hand later) and rendering.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/types.h"

namespace fp::sim {

/// An indexed triangle mesh. Closed (watertight) meshes give a meaningful inside/outside.
struct TriangleMesh {
  std::vector<Vec3d> vertices;                          ///< positions [m]
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside

  /// Reads an OBJ file (v and f lines; polygons are fanned into triangles; normals and texture indices
  /// ignored). Throws InputError naming the file (and line) when it is missing, malformed or has no
  /// triangles.
  static TriangleMesh loadObj(const std::string& path);
  /// Writes an OBJ file; throws InputError when the file cannot be written.
  void saveObj(const std::string& path) const;

  /// bounding box of the vertices
  Aabb bounds() const;
  /// multiplies every vertex by `s`
  void scale(double s);
  /// total surface area [m^2]
  double area() const;
};

}  // namespace fp::sim
