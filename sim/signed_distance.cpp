#include "sim/signed_distance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <unordered_map>

namespace fp::sim {

namespace {

// Exact distances to the analytic shapes.

double boxSdf(const Vec3d& half, const Vec3d& p) {
  const Vec3d q = p.cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

double capsuleSdf(double radius, double halfLength, const Vec3d& p) {
  const double y = std::clamp(p.y(), -halfLength, halfLength);
  return (p - Vec3d(0.0, y, 0.0)).norm() - radius;
}

// ---------------------------------------------------------------------------------------------------------------
// Triangle meshes.

/// Which part of a triangle holds the closest point: a corner, an edge (opposite the corner of the same
/// number: edge 0 = v1v2, 1 = v2v0, 2 = v0v1), or the inside.
enum class Feature : std::uint8_t { Vertex0, Vertex1, Vertex2, Edge0, Edge1, Edge2, Face };

struct ClosestPoint {
  Vec3d point;
  Feature feature;
};

ClosestPoint closestOnSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b, Feature atA, Feature atB,
                              Feature inside) {
  const Vec3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? (p - a).dot(ab) / len2 : 0.0;
  if (t <= 0.0)
    return {a, atA};
  if (t >= 1.0)
    return {b, atB};
  return {a + t * ab, inside};
}

/// Closest point of triangle abc to p, with the feature it lies on (Ericson, Real-Time Collision
/// Detection, 5.1.5).
ClosestPoint closestOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0)
    return {a, Feature::Vertex0};
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3)
    return {b, Feature::Vertex1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
    return {a + d1 / (d1 - d3) * ab, Feature::Edge2};
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6)
    return {c, Feature::Vertex2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
    return {a + d2 / (d2 - d6) * ac, Feature::Edge1};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return {b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b), Feature::Edge0};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // Degenerate (zero-area) triangle: the closest point is on one of its edges.
    ClosestPoint best = closestOnSegment(p, b, c, Feature::Vertex1, Feature::Vertex2, Feature::Edge0);
    for (const ClosestPoint& cand :
         {closestOnSegment(p, c, a, Feature::Vertex2, Feature::Vertex0, Feature::Edge1),
          closestOnSegment(p, a, b, Feature::Vertex0, Feature::Vertex1, Feature::Edge2)}) {
      if ((cand.point - p).squaredNorm() < (best.point - p).squaredNorm())
        best = cand;
    }
    return best;
  }
  return {a + (vb / sum) * ab + (vc / sum) * ac, Feature::Face};
}

std::uint64_t bitsOf(double x) {
  x += 0.0;  // -0.0 -> +0.0, so that both weld together
  std::uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

struct PositionHash {
  std::size_t operator()(const std::array<std::uint64_t, 3>& k) const {
    std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
    h ^= k[1] + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
    h ^= k[2] + 0x94D049BB133111EBull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

std::uint32_t findRoot(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}
}  // namespace

std::shared_ptr<const MeshSdfData> buildMeshSdfData(const TriangleMesh& mesh) {
  auto data = std::make_shared<MeshSdfData>();
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  for (const auto& t : mesh.triangles) {
    for (std::uint32_t v : t) {
      if (v >= nv)
        throw InputError("mesh: triangle references vertex " + std::to_string(v) + " of " +
                         std::to_string(nv));
    }
  }
  data->normals.resize(nt);
  data->angles.resize(nt);
  data->centroids.resize(nt);
  data->spans.resize(nt);
  for (std::size_t i = 0; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    const Vec3d& a = mesh.vertices[t[0]];
    const Vec3d& b = mesh.vertices[t[1]];
    const Vec3d& c = mesh.vertices[t[2]];
    data->centroids[i] = (a + b + c) / 3.0;
    data->spans[i] = std::max(
        {(a - data->centroids[i]).norm(), (b - data->centroids[i]).norm(), (c - data->centroids[i]).norm()});
    const Vec3d n = (b - a).cross(c - a);
    const double len = n.norm();
    data->normals[i] = len > 0.0 ? Vec3d(n / len) : Vec3d::Zero();
    const std::array<Vec3d, 3> v{a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Vec3d e1 = v[(k + 1) % 3] - v[k], e2 = v[(k + 2) % 3] - v[k];
      // atan2 of |cross| and dot is accurate for angles near 0 and pi, unlike acos.
      data->angles[i][k] = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    }
  }

  // Components: triangles connected through shared vertices, vertices at bit-identical positions welded first
  // so that meshes written without shared indices (one vertex triple per triangle) are still one closed
  // component.
  std::unordered_map<std::array<std::uint64_t, 3>, std::uint32_t, PositionHash> weld;
  std::vector<std::uint32_t> parent(nv);
  for (std::uint32_t i = 0; i < nv; ++i) {
    const Vec3d& p = mesh.vertices[i];
    parent[i] = weld.emplace(std::array<std::uint64_t, 3>{bitsOf(p.x()), bitsOf(p.y()), bitsOf(p.z())}, i)
                    .first->second;
  }
  for (const auto& t : mesh.triangles) {
    const std::uint32_t r0 = findRoot(parent, t[0]);
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t rk = findRoot(parent, t[k]);
      if (rk != r0)
        parent[rk] = r0;
    }
  }
  std::unordered_map<std::uint32_t, std::uint32_t> componentOfRoot;
  for (std::uint32_t i = 0; i < nt; ++i) {
    const std::uint32_t root = findRoot(parent, mesh.triangles[i][0]);
    const auto [it, inserted] =
        componentOfRoot.emplace(root, static_cast<std::uint32_t>(data->components.size()));
    if (inserted) {
      data->components.emplace_back();
      data->componentBounds.emplace_back();
    }
    data->components[it->second].push_back(i);
    for (std::uint32_t v : mesh.triangles[i])
      data->componentBounds[it->second].extend(mesh.vertices[v]);
  }
  const Aabb box = mesh.bounds();
  data->tolerance = 1e-9 * (box.isEmpty() ? 1.0 : std::max(box.diagonal().norm(), 1e-30));
  return data;
}

/// Signed distance from p to one closed component: the distance to its closest triangle, signed by the
/// angle-weighted pseudo-normal of the closest feature (Baerentzen & Aanaes 2005). The pseudo-normal is
/// assembled from every triangle of the component whose closest point is the same point, each weighted by its
/// angle there (the corner angle at a vertex, pi on an edge, 2 pi inside), so no adjacency table is needed.
namespace {

/// The triangles of `tris` (in their order) that can lie within `slack` of the distance from p to the nearest
/// of them, written to `out`. A triangle's distance from p is at least |p - centroid| - span and at most
/// |p - centroid| (the centroid is one of its points), so the nearest is no farther than the smallest
/// |p - centroid|, and a triangle whose lower bound exceeds that by more than `slack` (plus the tolerance,
/// for round-off) is dropped without its closest point. The closest-point queries that decide are the same as
/// over all of `tris`, so the results are bit-identical; the propeller's 1,696 triangles leave a few dozen.
void trianglesWithin(const MeshSdfData& data, const std::vector<std::uint32_t>& tris, const Vec3d& p,
                     double slack, std::vector<std::uint32_t>& out) {
  thread_local std::vector<double> toCentroid2;
  toCentroid2.resize(tris.size());
  double nearest2 = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < tris.size(); ++k) {
    toCentroid2[k] = (p - data.centroids[tris[k]]).squaredNorm();
    nearest2 = std::min(nearest2, toCentroid2[k]);
  }
  const double limit = std::sqrt(nearest2) + slack + data.tolerance;
  out.clear();
  for (std::size_t k = 0; k < tris.size(); ++k) {
    const double reach = limit + data.spans[tris[k]];  // |p - centroid| - span <= limit, squared
    if (toCentroid2[k] <= reach * reach)
      out.push_back(tris[k]);
  }
}

/// componentSdf over `all`, a subset of one component's triangles (in the component's order) that holds
/// every triangle whose closest point to p is within the tolerance of the component's closest point
double sdfOverTriangles(const TriangleMesh& mesh, const MeshSdfData& data,
                        const std::vector<std::uint32_t>& all, const Vec3d& p) {
  if (all.empty())
    return std::numeric_limits<double>::infinity();
  // a triangle whose closest point is within the tolerance of the nearest one's is within it in distance
  thread_local std::vector<std::uint32_t> tris;
  trianglesWithin(data, all, p, data.tolerance, tris);
  if (tris.empty())  // a non-finite p keeps no triangle: no distance either
    return std::numeric_limits<double>::infinity();
  thread_local std::vector<ClosestPoint> closest;
  closest.resize(tris.size());
  double best = std::numeric_limits<double>::infinity();
  std::size_t bestIndex = 0;
  for (std::size_t k = 0; k < tris.size(); ++k) {
    const auto& t = mesh.triangles[tris[k]];
    closest[k] = closestOnTriangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
    const double d2 = (closest[k].point - p).squaredNorm();
    if (d2 < best) {
      best = d2;
      bestIndex = k;
    }
  }
  const Vec3d c = closest[bestIndex].point;
  const double distance = std::sqrt(best);
  if (distance == 0.0)
    return 0.0;
  Vec3d pseudoNormal = Vec3d::Zero();
  const double tol2 = data.tolerance * data.tolerance;
  for (std::size_t k = 0; k < tris.size(); ++k) {
    if ((closest[k].point - c).squaredNorm() > tol2)
      continue;
    const std::uint32_t tri = tris[k];
    double weight = 2.0 * kPi;
    switch (closest[k].feature) {
      case Feature::Vertex0:
        weight = data.angles[tri][0];
        break;
      case Feature::Vertex1:
        weight = data.angles[tri][1];
        break;
      case Feature::Vertex2:
        weight = data.angles[tri][2];
        break;
      case Feature::Edge0:
      case Feature::Edge1:
      case Feature::Edge2:
        weight = kPi;
        break;
      case Feature::Face:
        break;
    }
    pseudoNormal += weight * data.normals[tri];
  }
  return (p - c).dot(pseudoNormal) < 0.0 ? -distance : distance;
}

}  // namespace

double componentSdf(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t component,
                    const Vec3d& p) {
  return sdfOverTriangles(mesh, data, data.components[component], p);
}

namespace {

/// Signed distance to the union of the mesh's closed components. Overlapping components (a blade pushed into
/// a hub) are a union: the minimum of the per-component signed distances is negative inside any of them and
/// exact outside all of them (inside, its magnitude is the depth in the deepest component, a lower bound of
/// the true depth). Brute force over the triangles: O(triangles) per query.
double meshSdf(const TriangleMesh& mesh, const MeshSdfData& data, const Vec3d& p) {
  double result = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < data.components.size(); ++k) {
    result = std::min(result, componentSdf(mesh, data, k, p));
  }
  return result;
}
/// The per-mesh data of a collider's mesh, cached per thread (no locking on the hot path). Entries hold weak
/// pointers, so a freed mesh whose address is reused is never mistaken for the old one.
std::shared_ptr<const MeshSdfData> cachedMeshSdfData(const std::shared_ptr<const TriangleMesh>& mesh) {
  struct Entry {
    std::weak_ptr<const TriangleMesh> mesh;
    std::size_t vertexCount, triangleCount;
    std::shared_ptr<const MeshSdfData> data;
  };
  thread_local std::vector<Entry> cache;
  cache.erase(std::remove_if(cache.begin(), cache.end(), [](const Entry& e) { return e.mesh.expired(); }),
              cache.end());
  for (const Entry& e : cache) {
    if (e.mesh.lock() == mesh && e.vertexCount == mesh->vertices.size() &&
        e.triangleCount == mesh->triangles.size()) {
      return e.data;
    }
  }
  std::shared_ptr<const MeshSdfData> data = buildMeshSdfData(*mesh);
  if (cache.size() >= 16)
    cache.erase(cache.begin());
  cache.push_back({mesh, mesh->vertices.size(), mesh->triangles.size(), data});
  return data;
}

}  // namespace

double signedDistanceLocal(const ColliderDesc& collider, const Vec3d& localPoint) {
  switch (collider.shape) {
    case ShapeType::Box: {
      if (collider.container) {
        // the walls and the lid are those of the box raised by the headroom (see ColliderDesc::headroom)
        const Vec3d raise(0.0, 0.5 * collider.headroom, 0.0);
        return -boxSdf(collider.halfExtents + raise, localPoint - raise);
      }
      return boxSdf(collider.halfExtents, localPoint);
    }
    case ShapeType::Sphere:
      return localPoint.norm() - collider.radius;
    case ShapeType::Capsule:
      return capsuleSdf(collider.radius, collider.halfLength, localPoint);
    case ShapeType::Mesh: {
      if (!collider.mesh)
        throw InputError("collider '" + collider.name + "': mesh shape without a mesh");
      if (collider.mesh->triangles.empty()) {
        throw InputError("collider '" + collider.name + "': mesh has no triangles");
      }
      return meshSdf(*collider.mesh, *cachedMeshSdfData(collider.mesh), localPoint);
    }
  }
  throw InputError("collider '" + collider.name + "': unknown shape");
}

BallSdf::BallSdf(const ColliderDesc& collider, const Vec3d& localCentre, double radius)
    : m_collider(&collider) {
  if (collider.shape != ShapeType::Mesh || !collider.mesh || collider.mesh->triangles.empty()) {
    m_centre = signedDistanceLocal(collider, localCentre);
    return;
  }
  m_data = cachedMeshSdfData(collider.mesh);
  const TriangleMesh& mesh = *collider.mesh;
  // The unsigned distance to a component is 1-Lipschitz: at a point q of the ball it is at most d_k + radius
  // (d_k its distance from the centre), and a triangle farther than d_k + 2 radius from the centre is
  // farther than that from q, so it is never q's closest (the tolerance keeps the pseudo-normal's ties).
  m_subsets.resize(m_data->components.size());
  m_centre = std::numeric_limits<double>::infinity();
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < m_data->components.size(); ++k) {
    // the triangles that can be within 2 radius + 4 tolerance of the nearest (the reach below)
    thread_local std::vector<std::uint32_t> tris;
    trianglesWithin(*m_data, m_data->components[k], localCentre, 2.0 * radius + 4.0 * m_data->tolerance,
                    tris);
    thread_local std::vector<double> distance2;
    distance2.resize(tris.size());
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const auto& tri = mesh.triangles[tris[t]];
      const ClosestPoint c =
          closestOnTriangle(localCentre, mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]);
      distance2[t] = (c.point - localCentre).squaredNorm();
      best = std::min(best, distance2[t]);
      if (distance2[t] < nearest) {
        nearest = distance2[t];
        m_surfacePoint = c.point;
        m_hasSurfacePoint = true;
      }
    }
    const double reach = std::sqrt(best) + 2.0 * radius + 4.0 * m_data->tolerance;
    for (std::size_t t = 0; t < tris.size(); ++t) {
      if (distance2[t] <= reach * reach)
        m_subsets[k].push_back(tris[t]);
    }
    m_centre = std::min(m_centre, sdfOverTriangles(mesh, *m_data, m_subsets[k], localCentre));
  }
}

double BallSdf::operator()(const Vec3d& localPoint) const {
  if (!m_data)
    return signedDistanceLocal(*m_collider, localPoint);
  double result = std::numeric_limits<double>::infinity();
  for (const std::vector<std::uint32_t>& subset : m_subsets)
    result = std::min(result, sdfOverTriangles(*m_collider->mesh, *m_data, subset, localPoint));
  return result;
}

double signedDistance(const ColliderDesc& collider, const Vec3d& worldPoint) {
  // The orientation maps local -> world, so its inverse (the conjugate of the unit quaternion) maps back.
  const Vec3d local = collider.orientation.normalized().conjugate() * (worldPoint - collider.position);
  return signedDistanceLocal(collider, local);
}

}  // namespace fp::sim
