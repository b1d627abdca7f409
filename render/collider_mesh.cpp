#include "render/collider_mesh.h"

#include <algorithm>
#include <cmath>

namespace fp::render {

namespace {

void addVertex(MeshData& mesh, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  mesh.vertices.insert(mesh.vertices.end(), {p.x(), p.y(), p.z(), n.x(), n.y(), n.z()});
}

// A surface of revolution about y from a profile of (radius, height) points with outward profile normals.
void addRevolved(MeshData& mesh, const std::vector<Eigen::Vector2f>& profile,
                 const std::vector<Eigen::Vector2f>& normals, int segments) {
  auto point = [&](std::size_t k, int s, const std::vector<Eigen::Vector2f>& curve) {
    const float a = float(2.0 * sim::kPi) * float(s) / float(segments);
    return Eigen::Vector3f(curve[k].x() * std::cos(a), curve[k].y(), curve[k].x() * std::sin(a));
  };
  for (std::size_t k = 0; k + 1 < profile.size(); ++k) {
    for (int s = 0; s < segments; ++s) {
      const Eigen::Vector3f p00 = point(k, s, profile), p01 = point(k, s + 1, profile);
      const Eigen::Vector3f p10 = point(k + 1, s, profile), p11 = point(k + 1, s + 1, profile);
      const Eigen::Vector3f n00 = point(k, s, normals).normalized(),
                            n01 = point(k, s + 1, normals).normalized();
      const Eigen::Vector3f n10 = point(k + 1, s, normals).normalized();
      const Eigen::Vector3f n11 = point(k + 1, s + 1, normals).normalized();
      // the profile runs from bottom to top, so (p00, p10, p11) winds counter-clockwise seen from outside
      addVertex(mesh, p00, n00);
      addVertex(mesh, p10, n10);
      addVertex(mesh, p11, n11);
      addVertex(mesh, p00, n00);
      addVertex(mesh, p11, n11);
      addVertex(mesh, p01, n01);
    }
  }
}

}  // namespace

MeshData boxMesh(const Eigen::Vector3f& h) {
  MeshData mesh;
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign = -1; sign <= 1; sign += 2) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = float(sign);
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      Eigen::Vector3f corner[4];
      const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
      for (int c = 0; c < 4; ++c) {
        corner[c][axis] = float(sign) * h[axis];
        corner[c][u] = su[c] * h[u];
        corner[c][v] = sv[c] * h[v];
      }
      // u x v = axis, so the corners run counter-clockwise seen from +axis; flip for the -axis face
      const int order[6] = {0, 1, 2, 0, 2, 3};
      for (int k = 0; k < 6; ++k)
        addVertex(mesh, corner[sign > 0 ? order[k] : order[5 - k]], n);
    }
  }
  return mesh;
}

MeshData sphereMesh(float radius, int segments) {
  return capsuleMesh(radius, 0.0f, segments);
}

MeshData capsuleMesh(float radius, float halfLength, int segments) {
  std::vector<Eigen::Vector2f> profile, normals;
  const int stacks = std::max(2, segments / 4);
  for (int k = 0; k <= stacks; ++k) {  // bottom cap, from the pole up to the equator
    const float a = float(-0.5 * sim::kPi) + float(0.5 * sim::kPi) * float(k) / float(stacks);
    normals.emplace_back(std::cos(a), std::sin(a));
    profile.emplace_back(radius * std::cos(a), radius * std::sin(a) - halfLength);
  }
  for (int k = 0; k <= stacks; ++k) {  // top cap, from the equator up to the pole
    const float a = float(0.5 * sim::kPi) * float(k) / float(stacks);
    normals.emplace_back(std::cos(a), std::sin(a));
    profile.emplace_back(radius * std::cos(a), radius * std::sin(a) + halfLength);
  }
  MeshData mesh;
  addRevolved(mesh, profile, normals, segments);
  return mesh;
}

MeshData triangleMesh(const sim::TriangleMesh& source) {
  MeshData mesh;
  mesh.vertices.reserve(source.triangles.size() * 18);
  for (const auto& t : source.triangles) {
    const Eigen::Vector3f a = source.vertices[t[0]].cast<float>();
    const Eigen::Vector3f b = source.vertices[t[1]].cast<float>();
    const Eigen::Vector3f c = source.vertices[t[2]].cast<float>();
    const Eigen::Vector3f n = (b - a).cross(c - a).normalized();
    addVertex(mesh, a, n);
    addVertex(mesh, b, n);
    addVertex(mesh, c, n);
  }
  return mesh;
}

MeshData colliderMesh(const sim::ColliderDesc& collider) {
  switch (collider.shape) {
    case sim::ShapeType::Box:
      return boxMesh(collider.halfExtents.cast<float>());
    case sim::ShapeType::Sphere:
      return sphereMesh(float(collider.radius), 32);
    case sim::ShapeType::Capsule:
      return capsuleMesh(float(collider.radius), float(collider.halfLength), 32);
    case sim::ShapeType::Mesh:
      return collider.mesh ? triangleMesh(*collider.mesh) : MeshData{};
  }
  return {};
}

}  // namespace fp::render
