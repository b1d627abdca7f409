#pragma once
/// Signed distances to collider shapes (negative inside the solid), so that fluid and split children are
/// never placed in a wall: exact for boxes, containers, spheres and capsules; for triangle meshes the
/// distance to the closest triangle signed by the angle-weighted pseudo-normal (Baerentzen & Aanaes 2005),
/// with the per-mesh data built once and cached per thread.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "sim/mesh.h"
#include "sim/scene.h"
#include "sim/types.h"

namespace fp::sim {

/// Signed distance from a point in the collider's local frame to its surface: negative inside the solid. For
/// a container box the solid is the outside, so points inside the box have positive distance.
double signedDistanceLocal(const ColliderDesc& collider, const Vec3d& localPoint);
/// Signed distance of a world point to a collider at its initial pose.
double signedDistance(const ColliderDesc& collider, const Vec3d& worldPoint);

/// Per-mesh data of the signed distance: face normals, corner angles and the closed components. Built once
/// per mesh; the mesh sampler uses it too (corner angles, and the components to drop samples buried in
/// another component).
struct MeshSdfData {
  std::vector<Vec3d> normals;                          ///< unit face normals (zero for degenerate triangles)
  std::vector<std::array<double, 3>> angles;           ///< interior angle at each corner [rad]
  std::vector<std::vector<std::uint32_t>> components;  ///< triangles of each connected component
  std::vector<Aabb> componentBounds;                   ///< bounding box of each component
  std::vector<Vec3d> centroids;                        ///< centroid of each triangle: one of its points
  std::vector<double> spans;  ///< largest distance from a triangle's centroid to its corners [m]
  double tolerance = 0.0;     ///< closest points closer than this are one feature [m]
};

/// Builds the per-mesh data; throws InputError when a triangle references a missing vertex.
std::shared_ptr<const MeshSdfData> buildMeshSdfData(const TriangleMesh& mesh);
/// Signed distance from p (mesh frame) to closed component `component` of the mesh [m]
double componentSdf(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t component, const Vec3d& p);

/// The signed distance to one collider for points within `radius` of a centre (collider frame): the same
/// values as signedDistanceLocal there, for a mesh at the cost of the triangles that can be closest to a
/// point of the ball (one pass over all of them at construction). Keeps a reference to the collider.
class BallSdf {
 public:
  BallSdf(const ColliderDesc& collider, const Vec3d& localCentre, double radius);
  /// the signed distance at the centre [m]
  double atCentre() const { return m_centre; }
  /// the signed distance at a point within `radius` of the centre [m]
  double operator()(const Vec3d& localPoint) const;
  /// a point of the surface nearest the centre (collider frame), for meshes; false for the other shapes. The
  /// signed distance at any point q is at most |q - surfacePoint| (exactly the distance outside, negative
  /// inside).
  bool surfacePoint(Vec3d& point) const {
    point = m_surfacePoint;
    return m_hasSurfacePoint;
  }

 private:
  const ColliderDesc* m_collider;
  std::shared_ptr<const MeshSdfData> m_data;          // meshes only
  std::vector<std::vector<std::uint32_t>> m_subsets;  // per component: the triangles that can be closest
  double m_centre = 0.0;
  Vec3d m_surfacePoint = Vec3d::Zero();
  bool m_hasSurfacePoint = false;
};

}  // namespace fp::sim
