#include "sim/boundary_sampling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <utility>

#include "sim/signed_distance.h"

namespace fp::sim {

namespace {

/// Grids larger than this per axis are a unit mistake (metres vs millimetres), not a real scene.
constexpr double kMaxSegments = 1e6;

void checkSpacing(double spacing) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw InputError("boundary sampling: spacing must be positive and finite, got " +
                     std::to_string(spacing));
  }
}

void checkLength(const char* what, double value) {
  if (!(value >= 0.0) || !std::isfinite(value)) {
    throw InputError(std::string("boundary sampling: ") + what + " must be >= 0 and finite, got " +
                     std::to_string(value));
  }
}

/// Number of equal segments of at most `spacing` that cover `length` (0 for a zero length). The relative
/// slack keeps exact multiples (1.0 / 0.05 = 20.000000000000004) from getting one segment too many.
int segments(double length, double spacing) {
  if (length <= 0.0)
    return 0;
  const double n = std::ceil(length / spacing * (1.0 - 1e-12));
  if (n > kMaxSegments) {
    throw InputError("boundary sampling: " + std::to_string(length) + " m at spacing " +
                     std::to_string(spacing) + " m needs too many particles");
  }
  return std::max(1, static_cast<int>(n));
}

/// Number of equal arcs of a circle of radius `radius` spanning `angle` [rad] whose chords are at most
/// `spacing`. Chords rather than arcs, so that neighbours are never more than `spacing` apart in space.
int arcSegments(double radius, double angle, double spacing) {
  if (radius <= 0.0 || angle <= 0.0)
    return 0;
  const double half = std::asin(std::min(1.0, spacing / (2.0 * radius)));  // half the angle of one chord
  const double n = std::ceil(angle / (2.0 * half) * (1.0 - 1e-12));
  if (n > kMaxSegments) {
    throw InputError("boundary sampling: radius " + std::to_string(radius) + " m at spacing " +
                     std::to_string(spacing) + " m needs too many particles");
  }
  return std::max(1, static_cast<int>(n));
}

/// Cell key of the spatial hash used to thin mesh samples.
struct CellHash {
  std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
    return static_cast<std::size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
  }
};

}  // namespace

std::vector<Vec3d> sampleBoxSurface(const Vec3d& halfExtents, double spacing) {
  checkSpacing(spacing);
  for (int a = 0; a < 3; ++a)
    checkLength("box half extent", halfExtents[a]);
  // A regular grid on the whole box, keeping the nodes with at least one index on the boundary: faces, edges
  // and corners are covered exactly once. A flat axis (half extent 0) has a single node that is both
  // boundaries.
  std::array<int, 3> n{};
  std::array<double, 3> step{};
  for (int a = 0; a < 3; ++a) {
    n[a] = segments(2.0 * halfExtents[a], spacing);
    step[a] = n[a] > 0 ? 2.0 * halfExtents[a] / n[a] : 0.0;
  }
  auto coord = [&](int a, int i) {
    // The last node is placed exactly on the face, not at -h + n * step, which may miss by a rounding error.
    return i == n[a] ? halfExtents[a] : -halfExtents[a] + i * step[a];
  };
  std::vector<Vec3d> points;
  for (int i = 0; i <= n[0]; ++i) {
    const bool bi = i == 0 || i == n[0];
    for (int j = 0; j <= n[1]; ++j) {
      const bool bj = j == 0 || j == n[1];
      if (bi || bj) {
        for (int k = 0; k <= n[2]; ++k)
          points.emplace_back(coord(0, i), coord(1, j), coord(2, k));
      } else {
        points.emplace_back(coord(0, i), coord(1, j), coord(2, 0));
        if (n[2] > 0)
          points.emplace_back(coord(0, i), coord(1, j), coord(2, n[2]));
      }
    }
  }
  return points;
}

std::vector<Vec3d> sampleSphereSurface(double radius, double spacing) {
  checkSpacing(spacing);
  checkLength("sphere radius", radius);
  if (radius == 0.0)
    return {Vec3d::Zero()};
  // Fibonacci lattice: nearly hexagonal, so with N points the neighbour distance is about sqrt(2 A / (sqrt(3)
  // N)). Choosing N = 2 A / (sqrt(3) spacing^2) (1.15 A / spacing^2) puts neighbours about `spacing` apart.
  const double area = 4.0 * kPi * radius * radius;
  const double count = std::ceil(2.0 * area / (std::sqrt(3.0) * spacing * spacing));
  if (count > kMaxSegments * kMaxSegments)
    throw InputError("boundary sampling: sphere needs too many particles");
  const std::size_t n = std::max<std::size_t>(1, static_cast<std::size_t>(count));
  const double golden = kPi * (3.0 - std::sqrt(5.0));  // golden angle [rad]
  std::vector<Vec3d> points;
  points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(n);
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * static_cast<double>(i);
    points.push_back(radius * Vec3d(rho * std::cos(phi), rho * std::sin(phi), z));
  }
  return points;
}

std::vector<Vec3d> sampleCapsuleSurface(double radius, double halfLength, double spacing) {
  checkSpacing(spacing);
  checkLength("capsule radius", radius);
  checkLength("capsule half length", halfLength);
  if (radius == 0.0) {
    // A segment: points along y.
    const int ny = segments(2.0 * halfLength, spacing);
    std::vector<Vec3d> points;
    for (int k = 0; k <= ny; ++k) {
      points.emplace_back(0.0, k == ny ? halfLength : -halfLength + 2.0 * halfLength * k / std::max(ny, 1),
                          0.0);
    }
    return points;
  }
  std::vector<Vec3d> points;
  // A ring of radius rho at height y; odd rings are turned by half a step so that rings interleave.
  auto ring = [&](double rho, double y, bool odd) {
    const int m = arcSegments(rho, 2.0 * kPi, spacing);
    if (m <= 1 || rho <= 1e-12 * radius) {
      points.emplace_back(0.0, y, 0.0);
      return;
    }
    const double offset = odd ? kPi / m : 0.0;
    for (int i = 0; i < m; ++i) {
      const double a = offset + 2.0 * kPi * i / m;
      points.emplace_back(rho * std::cos(a), y, rho * std::sin(a));
    }
  };
  // Cylinder rings from y = -L to y = +L (one ring at y = 0 when L = 0).
  const int ny = segments(2.0 * halfLength, spacing);
  for (int k = 0; k <= ny; ++k) {
    const double y = k == ny ? halfLength : -halfLength + 2.0 * halfLength * k / std::max(ny, 1);
    ring(radius, y, k % 2 == 1);
  }
  // Hemispheres: latitude rings above the end rings of the cylinder, up to a single point at each pole.
  const int nl = arcSegments(radius, 0.5 * kPi, spacing);
  for (int j = 1; j <= nl; ++j) {
    const double lat = 0.5 * kPi * j / nl;
    const double rho = j == nl ? 0.0 : radius * std::cos(lat);
    const double h = radius * std::sin(lat);
    ring(rho, halfLength + h, (ny + j) % 2 == 1);
    ring(rho, -halfLength - h, j % 2 == 1);
  }
  return points;
}

std::vector<Vec3d> sampleMeshSurface(const TriangleMesh& mesh, double spacing) {
  checkSpacing(spacing);
  if (mesh.triangles.empty())
    return {};
  const std::shared_ptr<const MeshSdfData> data = buildMeshSdfData(mesh);
  const std::size_t nt = mesh.triangles.size();

  // Candidates on every triangle, in priority order so that the thinning keeps sharp features exactly
  // sampled: the mesh vertices first, then points along the edges, then a lattice inside each triangle. Each
  // candidate remembers its component to test it against the others.
  struct Candidate {
    Vec3d p;
    std::uint32_t component;
  };
  std::vector<std::uint32_t> componentOf(nt);
  for (std::uint32_t c = 0; c < data->components.size(); ++c) {
    for (std::uint32_t t : data->components[c])
      componentOf[t] = c;
  }
  std::vector<Candidate> candidates;
  std::vector<std::uint32_t> vertexComponent(mesh.vertices.size(), UINT32_MAX);
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::uint32_t v : mesh.triangles[t])
      vertexComponent[v] = componentOf[t];
  }
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (vertexComponent[v] != UINT32_MAX)
      candidates.push_back({mesh.vertices[v], vertexComponent[v]});
  }
  // Unique edges, endpoints in index order so the points of an edge shared by two triangles are
  // bit-identical.
  std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t>> edges;
  edges.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
      edges.push_back({{std::min(a, b), std::max(a, b)}, componentOf[t]});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(),
                          [](const auto& x, const auto& y) { return x.first == y.first; }),
              edges.end());
  for (const auto& [e, component] : edges) {
    const Vec3d& a = mesh.vertices[e.first];
    const Vec3d& b = mesh.vertices[e.second];
    const int n = segments((b - a).norm(), spacing);
    for (int k = 1; k < n; ++k)
      candidates.push_back({a + (b - a) * (static_cast<double>(k) / n), component});
  }
  // Inside: the lattice spanned by the two edges at the widest corner, divided so that both are at most
  // `spacing`.
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles[t];
    const std::array<Vec3d, 3> v{mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]};
    if (data->normals[t].squaredNorm() == 0.0)
      continue;  // degenerate: its edges already cover it
    int corner = 0;
    for (int k = 1; k < 3; ++k) {
      if (data->angles[t][k] > data->angles[t][corner])
        corner = k;
    }
    const Vec3d& o = v[corner];
    const Vec3d e1 = v[(corner + 1) % 3] - o, e2 = v[(corner + 2) % 3] - o;
    const int n = segments(std::max(e1.norm(), e2.norm()), spacing);
    for (int i = 1; i < n; ++i) {
      for (int j = 1; i + j < n; ++j) {
        candidates.push_back(
            {o + e1 * (static_cast<double>(i) / n) + e2 * (static_cast<double>(j) / n), componentOf[t]});
      }
    }
  }

  // Overlapping closed components form a union: a candidate inside another component is not on the surface of
  // the solid (the root of a blade inside the hub), and would put boundary particles inside the body.
  if (data->components.size() > 1) {
    std::vector<Candidate> kept;
    kept.reserve(candidates.size());
    for (const Candidate& c : candidates) {
      bool inside = false;
      for (std::size_t k = 0; k < data->components.size() && !inside; ++k) {
        if (k == c.component)
          continue;
        const Aabb& b = data->componentBounds[k];
        if ((c.p.array() < b.min().array()).any() || (c.p.array() > b.max().array()).any())
          continue;
        inside = componentSdf(mesh, *data, k, c.p) < -data->tolerance;
      }
      if (!inside)
        kept.push_back(c);
    }
    candidates.swap(kept);
  }

  // Greedy thinning with a spatial hash (cells of the exclusion radius): a candidate is kept unless a kept
  // point is closer than half the spacing. It merges the duplicates on shared edges and vertices and the
  // crowded points of small or thin triangles; every dropped candidate has a kept point within half the
  // spacing, so every triangle stays covered.
  const double rMin = 0.5 * spacing;
  const double rMin2 = rMin * rMin;
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<std::uint32_t>, CellHash> grid;
  std::vector<Vec3d> points;
  auto cellOf = [&](const Vec3d& p) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor(p.x() / rMin)),
                                       static_cast<std::int64_t>(std::floor(p.y() / rMin)),
                                       static_cast<std::int64_t>(std::floor(p.z() / rMin))};
  };
  for (const Candidate& c : candidates) {
    const std::array<std::int64_t, 3> cell = cellOf(c.p);
    bool crowded = false;
    for (std::int64_t dx = -1; dx <= 1 && !crowded; ++dx) {
      for (std::int64_t dy = -1; dy <= 1 && !crowded; ++dy) {
        for (std::int64_t dz = -1; dz <= 1 && !crowded; ++dz) {
          const auto it = grid.find({cell[0] + dx, cell[1] + dy, cell[2] + dz});
          if (it == grid.end())
            continue;
          for (std::uint32_t q : it->second) {
            if ((points[q] - c.p).squaredNorm() < rMin2) {
              crowded = true;
              break;
            }
          }
        }
      }
    }
    if (crowded)
      continue;
    grid[cell].push_back(static_cast<std::uint32_t>(points.size()));
    points.push_back(c.p);
  }
  return points;
}

std::vector<Vec3d> sampleColliderLocal(const ColliderDesc& collider, double spacing) {
  switch (collider.shape) {
    case ShapeType::Box: {
      if (!collider.container)
        return sampleBoxSurface(collider.halfExtents, spacing);
      // A container is sampled like a box: its walls are the same faces, only the solid side differs. Its
      // headroom raises the lid (the top face) and lengthens the walls up to it.
      checkLength("container headroom", collider.headroom);
      const Vec3d raise(0.0, 0.5 * collider.headroom, 0.0);
      std::vector<Vec3d> points = sampleBoxSurface(collider.halfExtents + raise, spacing);
      for (Vec3d& p : points)
        p += raise;
      return points;
    }
    case ShapeType::Sphere:
      return sampleSphereSurface(collider.radius, spacing);
    case ShapeType::Capsule:
      return sampleCapsuleSurface(collider.radius, collider.halfLength, spacing);
    case ShapeType::Mesh:
      if (!collider.mesh)
        throw InputError("collider '" + collider.name + "': mesh shape without a mesh");
      return sampleMeshSurface(*collider.mesh, spacing);
  }
  throw InputError("collider '" + collider.name + "': unknown shape");
}
}  // namespace fp::sim
