#pragma once
/// Signed distances to collider shapes (negative inside the solid), so that fluid and split children are
/// never placed in a wall: exact for boxes, containers, spheres and capsules; for triangle meshes the
/// distance to the closest triangle signed by the angle-weighted pseudo-normal (Baerentzen & Aanaes 2005),
/// found through a bounding-box tree per closed component, with the per-mesh data built once and cached per
/// thread.

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
  /// A node of a component's bounding-box tree: a leaf (count > 0) holds `count` triangles from `first` in
  /// the component's `treeTriangles`; an inner node's children are the nodes `first` and `first + 1`.
  struct TreeNode {
    Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();  ///< the box of the node's triangles
    std::uint32_t first = 0, count = 0;
  };
  std::vector<std::vector<TreeNode>> trees;  ///< per component, the root first
  std::vector<bool> closed;  ///< per component: every edge shared by exactly two of its triangles
  bool allClosed = true;     ///< every component closed
  std::vector<std::vector<std::uint32_t>> treeTriangles;  ///< per component, the leaves' triangles
  double tolerance = 0.0;  ///< closest points closer than this are one feature [m]
};

/// Builds the per-mesh data; throws InputError when a triangle references a missing vertex.
std::shared_ptr<const MeshSdfData> buildMeshSdfData(const TriangleMesh& mesh);
/// Signed distance from p (mesh frame) to closed component `component` of the mesh [m]
double componentSdf(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t component, const Vec3d& p);
/// componentSdf by a pass over every triangle of the component, without the tree: the reference the tree's
/// result equals bit for bit (tests)
double componentSdfOverAll(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t component,
                           const Vec3d& p);

/// The signed distance to one collider around a centre (collider frame): the distance at the centre, the
/// surface point nearest it, and signedDistanceLocal at other points, with the mesh's data looked up once.
/// Keeps a reference to the collider.
class BallSdf {
 public:
  BallSdf(const ColliderDesc& collider, const Vec3d& localCentre);
  /// the signed distance at the centre [m]
  double atCentre() const { return m_centre; }
  /// the signed distance at a point (collider frame) [m]: signedDistanceLocal's value
  double operator()(const Vec3d& localPoint) const;
  /// whether the signed distance at a point is at least `c` > 0: the same answer as (*this)(localPoint) >= c.
  /// For a mesh of closed components outside which the centre lies, the triangles within reach of the point
  /// decide it mostly without a distance: one nearer than c answers no; none within max(c, |point - centre| -
  /// atCentre()) answers yes (the signed distance is 1-Lipschitz, so the point is then outside, as the centre
  /// is).
  bool atLeast(const Vec3d& localPoint, double c) const;
  /// a point of the surface nearest the centre (collider frame), for meshes; false for the other shapes. The
  /// signed distance at any point q is at most |q - surfacePoint| (exactly the distance outside, negative
  /// inside).
  bool surfacePoint(Vec3d& point) const {
    point = m_surfacePoint;
    return m_hasSurfacePoint;
  }

 private:
  const ColliderDesc* m_collider;
  std::shared_ptr<const MeshSdfData> m_data;  // meshes only
  Vec3d m_centrePoint = Vec3d::Zero();
  double m_centre = 0.0;
  Vec3d m_surfacePoint = Vec3d::Zero();
  bool m_hasSurfacePoint = false;
};

}  // namespace fp::sim
