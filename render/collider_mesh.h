#pragma once
/// Triangle meshes of the collider shapes in their local frames, for drawing the scene.

#include <Eigen/Core>
#include <vector>

#include "sim/scene.h"

namespace fp::render {

/// Unindexed triangles, each vertex as position (3 floats, local frame [m]) then unit normal (3 floats).
struct MeshData {
  std::vector<float> vertices;  ///< 6 floats a vertex, 3 vertices a triangle
  /// number of vertices
  std::size_t vertexCount() const { return vertices.size() / 6; }
};

/// a box centred at the origin; normals point outwards
MeshData boxMesh(const Eigen::Vector3f& halfExtents);
/// a sphere centred at the origin with `segments` slices and segments / 2 stacks
MeshData sphereMesh(float radius, int segments);
/// a capsule along local y: a cylinder of half length `halfLength` capped by two half spheres
MeshData capsuleMesh(float radius, float halfLength, int segments);
/// an OBJ mesh with flat normals (one normal a face, so sharp blades stay sharp)
MeshData triangleMesh(const sim::TriangleMesh& mesh);
/// the mesh of a collider's shape, in its local frame
MeshData colliderMesh(const sim::ColliderDesc& collider);

}  // namespace fp::render
