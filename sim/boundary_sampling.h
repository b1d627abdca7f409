#pragma once
/// Surface sampling of collider shapes into boundary particles (Akinci et al. 2012 use one layer of particles
/// on the surface). The signed distances to the same shapes are in sim/signed_distance.h.

#include <vector>

#include "sim/mesh.h"
#include "sim/scene.h"
#include "sim/types.h"

namespace fp::sim {

/// Points on the surface of a box centred at the origin, about `spacing` apart, faces, edges and corners
/// covered.
std::vector<Vec3d> sampleBoxSurface(const Vec3d& halfExtents, double spacing);
/// Points on a sphere centred at the origin, about `spacing` apart (Fibonacci lattice).
std::vector<Vec3d> sampleSphereSurface(double radius, double spacing);
/// Points on a capsule along the local y axis (cap centres at y = +-halfLength), about `spacing` apart.
std::vector<Vec3d> sampleCapsuleSurface(double radius, double halfLength, double spacing);
/// Points on a triangle mesh surface, about `spacing` apart, every triangle covered, none closer than ~0.5
/// spacing to another.
std::vector<Vec3d> sampleMeshSurface(const TriangleMesh& mesh, double spacing);

/// Surface samples of a collider in its local frame (container boxes too: their walls are the box faces).
std::vector<Vec3d> sampleColliderLocal(const ColliderDesc& collider, double spacing);

}  // namespace fp::sim
