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

// a leaf holds at most this many triangles
constexpr std::uint32_t kTreeLeaf = 4;

/// A bounding-box tree over `tris` (reordered in place into the leaves' order; `centroid` by triangle index):
/// each inner node splits its triangles at the median of their centroids along the longest axis of the
/// centroids' box (ties by index, so the tree depends on the mesh alone). Depth at most log2 of the count,
/// plus one.
void buildTree(const TriangleMesh& mesh, const std::vector<Vec3d>& centroid,
               std::vector<MeshSdfData::TreeNode>& nodes, std::vector<std::uint32_t>& tris) {
  struct Task {
    std::uint32_t node, begin, end;
  };
  nodes.assign(1, {});
  std::vector<Task> tasks{{0, 0, std::uint32_t(tris.size())}};
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    Aabb box, centres;
    for (std::uint32_t k = task.begin; k < task.end; ++k) {
      for (std::uint32_t v : mesh.triangles[tris[k]])
        box.extend(mesh.vertices[v]);
      centres.extend(centroid[tris[k]]);
    }
    nodes[task.node].lo = box.min();
    nodes[task.node].hi = box.max();
    if (task.end - task.begin <= kTreeLeaf) {
      nodes[task.node].first = task.begin;
      nodes[task.node].count = task.end - task.begin;
      continue;
    }
    int axis = 0;
    centres.sizes().maxCoeff(&axis);
    const std::uint32_t mid = task.begin + (task.end - task.begin) / 2;
    std::nth_element(tris.begin() + task.begin, tris.begin() + mid, tris.begin() + task.end,
                     [&](std::uint32_t a, std::uint32_t b) {
                       const double ca = centroid[a][axis], cb = centroid[b][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const auto left = std::uint32_t(nodes.size());
    nodes[task.node].first = left;
    nodes[task.node].count = 0;
    nodes.resize(nodes.size() + 2);
    tasks.push_back({left, task.begin, mid});
    tasks.push_back({left + 1, mid, task.end});
  }
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
  for (std::size_t i = 0; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    const Vec3d& a = mesh.vertices[t[0]];
    const Vec3d& b = mesh.vertices[t[1]];
    const Vec3d& c = mesh.vertices[t[2]];
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
  const std::vector<std::uint32_t> welded = parent;  // each vertex's representative position
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
  // Closed: every edge (between welded positions) shared by exactly two of the component's triangles.
  for (const std::vector<std::uint32_t>& component : data->components) {
    std::unordered_map<std::uint64_t, std::uint32_t> edges;
    for (std::uint32_t t : component) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = welded[mesh.triangles[t][k]], b = welded[mesh.triangles[t][(k + 1) % 3]];
        ++edges[(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b)];
      }
    }
    const bool closed = std::all_of(edges.begin(), edges.end(), [](const auto& e) { return e.second == 2; });
    data->closed.push_back(closed);
    data->allClosed = data->allClosed && closed;
  }
  std::vector<Vec3d> centroids(nt);
  for (std::size_t i = 0; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    centroids[i] = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0;
  }
  for (const std::vector<std::uint32_t>& component : data->components) {
    data->trees.emplace_back();
    data->treeTriangles.push_back(component);
    buildTree(mesh, centroids, data->trees.back(), data->treeTriangles.back());
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

/// A triangle the tree query met: its index, closest point and squared distance.
struct Met {
  std::uint32_t tri;
  ClosestPoint closest;
  double d2;
};

/// Squared distance from p to the box [lo, hi] (zero inside): at most the squared distance to anything in it.
double boxDistance2(const Vec3d& lo, const Vec3d& hi, const Vec3d& p) {
  const Vec3d d = (lo - p).cwiseMax(p - hi).cwiseMax(0.0);
  return d.squaredNorm();
}

/// Whether closed component k lies farther than `floor` >= 0 from p (its box does): p is then outside it and
/// its signed distance exceeds `floor`. An open component never does (its pseudo-normal signs it negative
/// also behind it, far from any triangle).
bool closedAndBeyond(const MeshSdfData& data, std::size_t k, const Vec3d& p, double floor) {
  const Aabb& box = data.componentBounds[k];
  return data.closed[k] && boxDistance2(box.min(), box.max(), p) > floor * floor;
}

/// Walks component k's tree nearer child first, skipping every node whose box lies farther from p than
/// sqrt(limit2()) (read again at each node), and gives each triangle of the leaves it reaches to
/// visit(triangle, closest point, squared distance), which returns false to stop the walk. False when
/// stopped.
template <class Limit, class Visit>
bool walkTree(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t k, const Vec3d& p,
              const Limit& limit2, const Visit& visit) {
  const std::vector<MeshSdfData::TreeNode>& nodes = data.trees[k];
  const std::vector<std::uint32_t>& tris = data.treeTriangles[k];
  // (depth <= log2(count) + 1 < 33: one pending sibling a level)
  std::array<std::uint32_t, 64> stack;
  std::size_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const MeshSdfData::TreeNode& node = nodes[stack[--top]];
    if (boxDistance2(node.lo, node.hi, p) > limit2())
      continue;
    if (node.count > 0) {
      for (std::uint32_t s = node.first; s < node.first + node.count; ++s) {
        const auto& t = mesh.triangles[tris[s]];
        const ClosestPoint c =
            closestOnTriangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
        if (!visit(tris[s], c, (c.point - p).squaredNorm()))
          return false;
      }
      continue;
    }
    const MeshSdfData::TreeNode& a = nodes[node.first];
    const MeshSdfData::TreeNode& b = nodes[node.first + 1];
    const bool aFirst = boxDistance2(a.lo, a.hi, p) <= boxDistance2(b.lo, b.hi, p);
    stack[top++] = aFirst ? node.first + 1 : node.first;  // (the farther one waits)
    stack[top++] = aFirst ? node.first : node.first + 1;
  }
  return true;
}

/// The signed distance from p given the triangles `met` (in the component's order, holding every triangle
/// whose closest point is within the tolerance of the nearest one's): the distance to the first nearest,
/// signed by the angle-weighted pseudo-normal of the met triangles sharing its closest point.
double signedFromMet(const MeshSdfData& data, const std::vector<Met>& met, const Vec3d& p, Vec3d* nearest,
                     double* nearest2);

/// The signed distance from p to closed component k: the tree is walked nearer child first, and a node is
/// skipped when its box lies farther than the nearest triangle so far plus two tolerances. Every triangle
/// whose closest point is within the tolerance of the nearest one's is then met, and the distance and
/// pseudo-normal are assembled from the met triangles in the component's order (ascending index), which
/// makes the result the one a pass over all of the component's triangles gives, bit for bit. `nearest`, when
/// given, receives the nearest closest point (the first in that order at the smallest distance) and its
/// squared distance.
double treeSdf(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t k, const Vec3d& p,
               Vec3d* nearest = nullptr, double* nearest2 = nullptr) {
  if (!p.allFinite())
    return std::numeric_limits<double>::infinity();
  thread_local std::vector<Met> met;
  met.clear();
  double best2 = std::numeric_limits<double>::infinity();
  auto limit2 = [&] {
    const double limit = std::sqrt(best2) + 2.0 * data.tolerance;
    return limit * limit;
  };
  walkTree(mesh, data, k, p, limit2, [&](std::uint32_t tri, const ClosestPoint& c, double d2) {
    best2 = std::min(best2, d2);
    met.push_back({tri, c, d2});
    return true;
  });
  // the triangles that can matter, in the component's order
  const double keep2 = limit2();
  met.erase(std::remove_if(met.begin(), met.end(), [&](const Met& m) { return !(m.d2 <= keep2); }),
            met.end());
  std::sort(met.begin(), met.end(), [](const Met& a, const Met& b) { return a.tri < b.tri; });
  return signedFromMet(data, met, p, nearest, nearest2);
}

double signedFromMet(const MeshSdfData& data, const std::vector<Met>& met, const Vec3d& p, Vec3d* nearest,
                     double* nearest2) {
  if (met.empty())
    return std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  std::size_t bestIndex = 0;
  for (std::size_t s = 0; s < met.size(); ++s) {
    if (met[s].d2 < best) {
      best = met[s].d2;
      bestIndex = s;
    }
  }
  const Vec3d c = met[bestIndex].closest.point;
  if (nearest)
    *nearest = c;
  if (nearest2)
    *nearest2 = best;
  const double distance = std::sqrt(best);
  if (distance == 0.0)
    return 0.0;
  Vec3d pseudoNormal = Vec3d::Zero();
  const double tol2 = data.tolerance * data.tolerance;
  for (const Met& m : met) {
    if ((m.closest.point - c).squaredNorm() > tol2)
      continue;
    double weight = 2.0 * kPi;
    switch (m.closest.feature) {
      case Feature::Vertex0:
        weight = data.angles[m.tri][0];
        break;
      case Feature::Vertex1:
        weight = data.angles[m.tri][1];
        break;
      case Feature::Vertex2:
        weight = data.angles[m.tri][2];
        break;
      case Feature::Edge0:
      case Feature::Edge1:
      case Feature::Edge2:
        weight = kPi;
        break;
      case Feature::Face:
        break;
    }
    pseudoNormal += weight * data.normals[m.tri];
  }
  return (p - c).dot(pseudoNormal) < 0.0 ? -distance : distance;
}

}  // namespace

double componentSdf(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t component,
                    const Vec3d& p) {
  return treeSdf(mesh, data, component, p);
}

double componentSdfOverAll(const TriangleMesh& mesh, const MeshSdfData& data, std::size_t component,
                           const Vec3d& p) {
  if (!p.allFinite())
    return std::numeric_limits<double>::infinity();
  std::vector<Met> met;
  for (std::uint32_t tri : data.components[component]) {
    const auto& t = mesh.triangles[tri];
    const ClosestPoint c =
        closestOnTriangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
    met.push_back({tri, c, (c.point - p).squaredNorm()});
  }
  return signedFromMet(data, met, p, nullptr, nullptr);
}

namespace {

/// Signed distance to the union of the mesh's closed components. Overlapping components (a blade pushed into
/// a hub) are a union: the minimum of the per-component signed distances is negative inside any of them and
/// exact outside all of them (inside, its magnitude is the depth in the deepest component, a lower bound of
/// the true depth). Each component through its tree: about the logarithm of its triangle count a query.
double meshSdf(const TriangleMesh& mesh, const MeshSdfData& data, const Vec3d& p) {
  double result = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < data.components.size(); ++k) {
    // a closed component farther than max(the distance so far, 0) plus four tolerances leaves the minimum
    if (result < std::numeric_limits<double>::infinity() &&
        closedAndBeyond(data, k, p, std::max(result, 0.0) + 4.0 * data.tolerance))
      continue;
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

BallSdf::BallSdf(const ColliderDesc& collider, const Vec3d& localCentre)
    : m_collider(&collider), m_centrePoint(localCentre) {
  if (collider.shape != ShapeType::Mesh || !collider.mesh || collider.mesh->triangles.empty()) {
    m_centre = signedDistanceLocal(collider, localCentre);
    return;
  }
  m_data = cachedMeshSdfData(collider.mesh);
  m_centre = std::numeric_limits<double>::infinity();
  double nearest2 = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < m_data->components.size(); ++k) {
    // (as in meshSdf: a closed component whose box lies beyond the nearest surface so far holds neither a
    // nearer surface point nor a smaller distance; the distance so far is at most the nearest's)
    if (nearest2 < std::numeric_limits<double>::infinity() &&
        closedAndBeyond(*m_data, k, localCentre, std::sqrt(nearest2) + 4.0 * m_data->tolerance))
      continue;
    Vec3d point = Vec3d::Zero();
    double d2 = std::numeric_limits<double>::infinity();
    m_centre = std::min(m_centre, treeSdf(*collider.mesh, *m_data, k, localCentre, &point, &d2));
    if (d2 < nearest2) {
      nearest2 = d2;
      m_surfacePoint = point;
      m_hasSurfacePoint = true;
    }
  }
}

double BallSdf::operator()(const Vec3d& localPoint) const {
  if (!m_data)
    return signedDistanceLocal(*m_collider, localPoint);
  return meshSdf(*m_collider->mesh, *m_data, localPoint);
}

bool BallSdf::atLeast(const Vec3d& localPoint, double c) const {
  // (the argument below needs closed components, a finite centre outside them and a clearance well above the
  // margins)
  if (!m_data || !m_data->allClosed || !(m_centre > 0.0) || !std::isfinite(m_centre) ||
      !m_centrePoint.allFinite() || !(c > 8.0 * m_data->tolerance) || !localPoint.allFinite())
    return (*this)(localPoint) >= c;
  // Every component's signed distance is 1-Lipschitz and positive at the centre. If no triangle lies within
  // R > |q - centre| - atCentre of q, none can vanish on the segment from the centre to q (there it is at
  // least atCentre - t, t from the centre, and at least R - (|q - centre| - t) in magnitude): q is outside
  // every component, at least R from each, and with R >= c the answer is yes. A triangle nearer than c
  // answers no whatever the sign. The margins keep both answers those of the computed distance.
  const double tol = m_data->tolerance;
  const double reach = std::max(c, (localPoint - m_centrePoint).norm() - m_centre) + 4.0 * tol;
  const double reach2 = reach * reach;
  const double below2 = (c - 4.0 * tol) * (c - 4.0 * tol);
  bool undecided = false;
  for (std::size_t k = 0; k < m_data->components.size(); ++k) {
    if (closedAndBeyond(*m_data, k, localPoint, reach))
      continue;
    const bool nearerThanC = !walkTree(
        *m_collider->mesh, *m_data, k, localPoint, [reach2] { return reach2; },
        [&](std::uint32_t, const ClosestPoint&, double d2) {
          undecided = undecided || d2 <= reach2;
          return !(d2 < below2);  // (a triangle nearer than c: no)
        });
    if (nearerThanC)
      return false;
  }
  return undecided ? (*this)(localPoint) >= c : true;
}

double signedDistance(const ColliderDesc& collider, const Vec3d& worldPoint) {
  // The orientation maps local -> world, so its inverse (the conjugate of the unit quaternion) maps back.
  const Vec3d local = collider.orientation.normalized().conjugate() * (worldPoint - collider.position);
  return signedDistanceLocal(collider, local);
}

}  // namespace fp::sim
