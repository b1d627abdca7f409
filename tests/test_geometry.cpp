// Geometry of colliders: OBJ meshes, boundary surface sampling and signed distances.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sim/boundary_sampling.h"
#include "sim/mesh.h"
#include "sim/signed_distance.h"
#include "tests/temp_path.h"

namespace fp::sim {
namespace {

using test::tempPath;

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = tempPath(name);
  std::ofstream(path) << text;
  return path;
}

/// The axis-aligned cube [-0.5, 0.5]^3 as quads, counter-clockwise seen from outside.
const char* kUnitCubeObj =
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 3 4 8 7\nf 2 3 7 6\nf 1 5 8 4\n";

/// Distance from every point to its nearest other point: {smallest, largest}. Brute force, for test sizes.
std::pair<double, double> nearestNeighbourRange(const std::vector<Vec3d>& points) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (j != i)
        best = std::min(best, (points[i] - points[j]).squaredNorm());
    }
    lo = std::min(lo, best);
    hi = std::max(hi, best);
  }
  return {std::sqrt(lo), std::sqrt(hi)};
}

double distanceToNearest(const std::vector<Vec3d>& points, const Vec3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Vec3d& q : points)
    best = std::min(best, (q - p).squaredNorm());
  return std::sqrt(best);
}

ColliderDesc boxCollider(const Vec3d& half) {
  ColliderDesc c;
  c.name = "box";
  c.shape = ShapeType::Box;
  c.halfExtents = half;
  return c;
}

ColliderDesc sphereCollider(double radius) {
  ColliderDesc c;
  c.name = "sphere";
  c.shape = ShapeType::Sphere;
  c.radius = radius;
  return c;
}

ColliderDesc capsuleCollider(double radius, double halfLength) {
  ColliderDesc c;
  c.name = "capsule";
  c.shape = ShapeType::Capsule;
  c.radius = radius;
  c.halfLength = halfLength;
  return c;
}

ColliderDesc meshCollider(std::shared_ptr<const TriangleMesh> mesh) {
  ColliderDesc c;
  c.name = "mesh";
  c.shape = ShapeType::Mesh;
  c.mesh = std::move(mesh);
  return c;
}

// --- OBJ meshes
// ---------------------------------------------------------------------------------------------------

TEST(MeshTest, ObjRoundTripIsExact) {
  TriangleMesh mesh;
  mesh.vertices = {Vec3d(0.1, -1.0 / 3.0, 2e-17), Vec3d(1.0, 2.0, 3.0), Vec3d(-4.5, 1e8, 0.7),
                   Vec3d(1.0 / 7.0, 0.0, -0.0)};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 2, 1}};
  const std::string path = tempPath("round.obj");
  mesh.saveObj(path);
  const TriangleMesh loaded = TriangleMesh::loadObj(path);
  ASSERT_EQ(loaded.vertices.size(), mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    EXPECT_EQ(loaded.vertices[i], mesh.vertices[i]) << i;
  EXPECT_EQ(loaded.triangles, mesh.triangles);
}

TEST(MeshTest, ObjFaceFormatsPolygonsAndIgnoredLines) {
  const std::string path = writeFile("formats.obj",
                                     "# comment\nmtllib x.mtl\no thing\ng group\ns 1\nusemtl red\n"
                                     "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
                                     "f 1/1 2/2 3/3\n"
                                     "f 1//1 3//1 4//1\n"
                                     "f 1/1/1 2/2/1 3/3/1\n"
                                     "f -4 -3 -2 -1\n"
                                     "\tf  1 2\t3  \r\n");
  const TriangleMesh m = TriangleMesh::loadObj(path);
  EXPECT_EQ(m.vertices.size(), 4u);
  const std::vector<std::array<std::uint32_t, 3>> expected = {{0, 1, 2}, {0, 2, 3}, {0, 1, 2},
                                                              {0, 1, 2}, {0, 2, 3}, {0, 1, 2}};
  EXPECT_EQ(m.triangles, expected);
}

TEST(MeshTest, MalformedObjNamesFileAndLine) {
  const std::string header = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";  // lines 1-3
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"bad_number", "v 1 2 x\n"}, {"few_coords", "v 1 2\n"},     {"huge", "v 1e999 0 0\n"},
      {"nan", "v nan 0 0\n"},      {"out_of_range", "f 1 2 4\n"}, {"zero", "f 0 1 2\n"},
      {"negative", "f -4 1 2\n"},  {"bad_index", "f 1 a 2\n"},    {"two_corners", "f 1 2\n"},
      {"bad_slash", "f 1 2 /3\n"}, {"trailing", "v 1 2 3x\n"},
  };
  for (const auto& [name, line] : cases) {
    const std::string path = writeFile(name + ".obj", header + line + "f 1 2 3\n");
    try {
      TriangleMesh::loadObj(path);
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path + ":4"), std::string::npos) << name << ": " << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << name << ": " << msg;
    }
  }
}

TEST(MeshTest, MissingFileAndNoTriangles) {
  const std::string missing = tempPath("does_not_exist.obj");
  try {
    TriangleMesh::loadObj(missing);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(missing), std::string::npos) << msg;
    EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
  }
  const std::string empty = writeFile("empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  try {
    TriangleMesh::loadObj(empty);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(empty), std::string::npos) << msg;
    EXPECT_NE(msg.find("no triangles"), std::string::npos) << msg;
  }
  TriangleMesh m;
  m.vertices = {Vec3d::Zero()};
  m.triangles = {{0, 0, 0}};
  EXPECT_THROW(m.saveObj(tempPath("no_such_dir/x.obj")), InputError);
}

TEST(MeshTest, BoundsScaleArea) {
  TriangleMesh m = TriangleMesh::loadObj(writeFile("cube.obj", kUnitCubeObj));
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_NEAR(m.area(), 6.0, 1e-12);
  m.scale(2.0);
  EXPECT_NEAR(m.area(), 24.0, 1e-12);
  const Aabb b = m.bounds();
  EXPECT_EQ(b.min(), Vec3d(-1, -1, -1));
  EXPECT_EQ(b.max(), Vec3d(1, 1, 1));
}

// --- surface sampling
// ---------------------------------------------------------------------------------------------

/// Checks the common properties of a surface sampling: on the surface, neighbours within `spacing`, none
/// closer than half of it, and a count close to area / spacing^2.
void expectGoodSampling(const std::vector<Vec3d>& points, const ColliderDesc& shape, double spacing,
                        double area) {
  ASSERT_FALSE(points.empty());
  double worst = 0.0;
  for (const Vec3d& p : points)
    worst = std::max(worst, std::abs(signedDistanceLocal(shape, p)));
  EXPECT_LT(worst, 1e-9);
  const auto [lo, hi] = nearestNeighbourRange(points);
  EXPECT_LE(hi, 1.01 * spacing);
  EXPECT_GE(lo, 0.5 * spacing * (1.0 - 1e-9));
  const double ratio = static_cast<double>(points.size()) / (area / (spacing * spacing));
  EXPECT_GT(ratio, 0.9);
  EXPECT_LT(ratio, 1.4);
}

TEST(SamplingTest, BoxCoversFacesEdgesAndCorners) {
  for (const auto& [half, spacing] : {std::pair<Vec3d, double>{Vec3d(0.5, 0.3, 0.2), 0.05},
                                      std::pair<Vec3d, double>{Vec3d(0.37, 0.21, 0.13), 0.04}}) {
    SCOPED_TRACE(spacing);
    const std::vector<Vec3d> points = sampleBoxSurface(half, spacing);
    const double area = 8.0 * (half.x() * half.y() + half.y() * half.z() + half.z() * half.x());
    expectGoodSampling(points, boxCollider(half), spacing, area);
    // Every corner is a sample, exactly.
    for (int c = 0; c < 8; ++c) {
      const Vec3d corner((c & 1) ? half.x() : -half.x(), (c & 2) ? half.y() : -half.y(),
                         (c & 4) ? half.z() : -half.z());
      EXPECT_EQ(distanceToNearest(points, corner), 0.0) << corner.transpose();
    }
    // Random surface points are within half a cell diagonal of a sample.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    double cover = 0.0;
    for (int i = 0; i < 2000; ++i) {
      Vec3d p(u(rng) * half.x(), u(rng) * half.y(), u(rng) * half.z());
      const int axis = i % 3;
      p[axis] = (i % 2 ? 1.0 : -1.0) * half[axis];
      cover = std::max(cover, distanceToNearest(points, p));
    }
    EXPECT_LE(cover, spacing / std::sqrt(2.0) + 1e-12);
  }
  // The exact count of the 0.5 x 0.3 x 0.2 box at 0.05: a 21 x 13 x 9 grid minus its 19 x 11 x 7 inside.
  EXPECT_EQ(sampleBoxSurface(Vec3d(0.5, 0.3, 0.2), 0.05).size(), 21u * 13u * 9u - 19u * 11u * 7u);
}

TEST(SamplingTest, SphereFibonacciLattice) {
  const double radius = 0.3, spacing = 0.03;
  const std::vector<Vec3d> points = sampleSphereSurface(radius, spacing);
  expectGoodSampling(points, sphereCollider(radius), spacing, 4.0 * kPi * radius * radius);
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  double cover = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3d p = radius * Vec3d(g(rng), g(rng), g(rng)).normalized();
    cover = std::max(cover, distanceToNearest(points, p));
  }
  EXPECT_LE(cover, 0.75 * spacing);
  // Deterministic.
  EXPECT_EQ(points, sampleSphereSurface(radius, spacing));
}

TEST(SamplingTest, CapsuleRingsAndHemispheres) {
  for (const auto& [radius, halfLength] :
       {std::pair{0.1, 0.2}, std::pair{0.07, 0.0}, std::pair{0.05, 0.33}}) {
    SCOPED_TRACE(halfLength);
    const double spacing = 0.02;
    const std::vector<Vec3d> points = sampleCapsuleSurface(radius, halfLength, spacing);
    const double area = 4.0 * kPi * radius * radius + 4.0 * kPi * radius * halfLength;
    expectGoodSampling(points, capsuleCollider(radius, halfLength), spacing, area);
    // Both poles are sampled; random surface points are covered.
    EXPECT_LT(distanceToNearest(points, Vec3d(0, halfLength + radius, 0)), 1e-12);
    EXPECT_LT(distanceToNearest(points, Vec3d(0, -halfLength - radius, 0)), 1e-12);
    std::mt19937 rng(5);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> u(-halfLength, halfLength);
    double cover = 0.0;
    for (int i = 0; i < 2000; ++i) {
      Vec3d d = Vec3d(g(rng), g(rng), g(rng)).normalized();
      Vec3d p;
      if (i % 2 == 0) {
        p = radius * d + Vec3d(0, d.y() > 0 ? halfLength : -halfLength, 0);  // on a cap
      } else {
        d.y() = 0.0;
        p = radius * d.normalized() + Vec3d(0, u(rng), 0);  // on the cylinder
      }
      cover = std::max(cover, distanceToNearest(points, p));
    }
    EXPECT_LE(cover, 0.75 * spacing);
  }
}

TEST(SamplingTest, MeshCubeSamplesCoverEveryTriangle) {
  auto mesh =
      std::make_shared<const TriangleMesh>(TriangleMesh::loadObj(writeFile("cube.obj", kUnitCubeObj)));
  const double spacing = 0.1;
  const std::vector<Vec3d> points = sampleMeshSurface(*mesh, spacing);
  const ColliderDesc collider = meshCollider(mesh);
  for (const Vec3d& p : points)
    ASSERT_LT(std::abs(signedDistanceLocal(collider, p)), 1e-12) << p.transpose();
  const auto [lo, hi] = nearestNeighbourRange(points);
  EXPECT_GE(lo, 0.5 * spacing * (1.0 - 1e-9));
  EXPECT_LE(hi, 1.01 * spacing);
  const double ratio = static_cast<double>(points.size()) / (6.0 / (spacing * spacing));
  EXPECT_GT(ratio, 0.9);
  EXPECT_LT(ratio, 1.5);
  // Every corner is sampled, and every point of every triangle is within one spacing of a sample.
  for (const Vec3d& v : mesh->vertices)
    EXPECT_EQ(distanceToNearest(points, v), 0.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const auto& t : mesh->triangles) {
    double cover = 0.0;
    for (int i = 0; i < 200; ++i) {
      double a = u(rng), b = u(rng);
      if (a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
      }
      const Vec3d& v0 = mesh->vertices[t[0]];
      const Vec3d p = v0 + a * (mesh->vertices[t[1]] - v0) + b * (mesh->vertices[t[2]] - v0);
      cover = std::max(cover, distanceToNearest(points, p));
    }
    EXPECT_LE(cover, spacing);
  }
  EXPECT_EQ(points, sampleMeshSurface(*mesh, spacing));  // deterministic
}

TEST(SamplingTest, ColliderDispatchAndErrors) {
  ColliderDesc container = boxCollider(Vec3d(0.4, 0.3, 0.2));
  container.container = true;
  EXPECT_EQ(sampleColliderLocal(container, 0.05), sampleBoxSurface(Vec3d(0.4, 0.3, 0.2), 0.05));
  EXPECT_EQ(sampleColliderLocal(sphereCollider(0.2), 0.05), sampleSphereSurface(0.2, 0.05));
  EXPECT_EQ(sampleColliderLocal(capsuleCollider(0.1, 0.2), 0.05), sampleCapsuleSurface(0.1, 0.2, 0.05));
  EXPECT_THROW(sampleColliderLocal(meshCollider(nullptr), 0.05), InputError);
  EXPECT_THROW(sampleBoxSurface(Vec3d(1, 1, 1), 0.0), InputError);
  EXPECT_THROW(sampleSphereSurface(-1.0, 0.1), InputError);
}

// --- signed distances
// ---------------------------------------------------------------------------------------------

TEST(SdfTest, AnalyticShapes) {
  const ColliderDesc box = boxCollider(Vec3d(1, 2, 3));
  EXPECT_NEAR(signedDistanceLocal(box, Vec3d(0, 0, 0)), -1.0, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(box, Vec3d(0, 1.5, 0)), -0.5, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(box, Vec3d(2, 0, 0)), 1.0, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(box, Vec3d(2, 3, 4)), std::sqrt(3.0), 1e-15);        // off a corner
  EXPECT_NEAR(signedDistanceLocal(box, Vec3d(-1, -2.5, 3.5)), std::sqrt(0.5), 1e-15);  // off an edge
  ColliderDesc container = box;
  container.container = true;
  EXPECT_NEAR(signedDistanceLocal(container, Vec3d(0, 0, 0)), 1.0, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(container, Vec3d(2, 3, 4)), -std::sqrt(3.0), 1e-15);

  const ColliderDesc sphere = sphereCollider(0.5);
  EXPECT_NEAR(signedDistanceLocal(sphere, Vec3d(0, 0, 0)), -0.5, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(sphere, Vec3d(0.6, 0.8, 0)), 0.5, 1e-15);

  const ColliderDesc capsule = capsuleCollider(0.1, 0.2);
  EXPECT_NEAR(signedDistanceLocal(capsule, Vec3d(0, 0, 0)), -0.1, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(capsule, Vec3d(0.3, 0.15, 0)), 0.2, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(capsule, Vec3d(0, -0.5, 0)), 0.2, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(capsule, Vec3d(0.3, 0.6, 0)), 0.4, 1e-15);
  EXPECT_NEAR(signedDistanceLocal(capsule, Vec3d(0, 0.25, 0.04)), -0.1 + std::sqrt(0.0025 + 0.0016), 1e-15);
}

TEST(SdfTest, WorldPointsUseThePose) {
  ColliderDesc box = boxCollider(Vec3d(1.0, 0.5, 0.5));
  box.position = Vec3d(1, 2, 3);
  box.orientation = Quatd(Eigen::AngleAxisd(0.5 * kPi, Vec3d::UnitZ()));
  // Local +x is world +y: 1.5 along world y is 0.5 beyond the long half extent.
  EXPECT_NEAR(signedDistance(box, box.position + Vec3d(0, 1.5, 0)), 0.5, 1e-12);
  // 1.5 along world x is 1.5 along local -y: 1.0 beyond the short half extent.
  EXPECT_NEAR(signedDistance(box, box.position + Vec3d(1.5, 0, 0)), 1.0, 1e-12);
  EXPECT_NEAR(signedDistance(box, box.position), -0.5, 1e-12);
}

TEST(SdfTest, MeshCubeMatchesBox) {
  auto mesh =
      std::make_shared<const TriangleMesh>(TriangleMesh::loadObj(writeFile("cube.obj", kUnitCubeObj)));
  const ColliderDesc cube = meshCollider(mesh);
  const ColliderDesc box = boxCollider(Vec3d(0.5, 0.5, 0.5));
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<Vec3d> points;
  for (int i = 0; i < 3000; ++i)
    points.emplace_back(u(rng), u(rng), u(rng));
  // Points whose closest feature is an edge or a corner (where face normals alone give wrong signs), and
  // points just inside and outside a face.
  for (double d : {1e-6, 1e-3, 0.2}) {
    points.emplace_back(0.5 + d, 0.5 + d, 0.1);
    points.emplace_back(0.5 - d, 0.5 - d, 0.1);
    points.emplace_back(0.5 + d, 0.5 + d, 0.5 + d);
    points.emplace_back(0.5 - d, 0.5 - d, 0.5 - d);
    points.emplace_back(-0.5 - d, 0.2, 0.3);
    points.emplace_back(-0.5 + d, 0.2, 0.3);
    points.emplace_back(0.5 + d, 0.5 - 0.5 * d, -0.5 + 2.0 * d);
  }
  for (const Vec3d& p : points) {
    ASSERT_NEAR(signedDistanceLocal(cube, p), signedDistanceLocal(box, p), 1e-9) << p.transpose();
  }
}

TEST(SdfTest, MeshOverlappingComponentsFormAUnion) {
  // Two cubes overlapping in 0.1 < x < 0.5: A centred at the origin, B at x = 0.6.
  TriangleMesh cubes = TriangleMesh::loadObj(writeFile("cube.obj", kUnitCubeObj));
  const std::size_t n = cubes.vertices.size();
  for (std::size_t i = 0; i < n; ++i)
    cubes.vertices.push_back(cubes.vertices[i] + Vec3d(0.6, 0, 0));
  const std::size_t nt = cubes.triangles.size();
  for (std::size_t i = 0; i < nt; ++i) {
    auto t = cubes.triangles[i];
    for (auto& v : t)
      v += static_cast<std::uint32_t>(n);
    cubes.triangles.push_back(t);
  }
  const ColliderDesc c = meshCollider(std::make_shared<const TriangleMesh>(std::move(cubes)));
  // Inside A only, but the nearest triangle (B's face at x = 0.1) faces away: still inside.
  EXPECT_NEAR(signedDistanceLocal(c, Vec3d(-0.15, 0, 0)), -0.35, 1e-12);
  // Inside both: the depth in the deeper one.
  EXPECT_NEAR(signedDistanceLocal(c, Vec3d(0.15, 0, 0)), -0.35, 1e-12);
  // Outside both: the exact distance to the union.
  EXPECT_NEAR(signedDistanceLocal(c, Vec3d(1.5, 0, 0)), 0.4, 1e-12);
  EXPECT_NEAR(signedDistanceLocal(c, Vec3d(0.3, 0.8, 0)), 0.3, 1e-12);
  // Samples inside the other cube are dropped: none is strictly inside the union.
  for (const Vec3d& p : sampleMeshSurface(*c.mesh, 0.05)) {
    ASSERT_GT(signedDistanceLocal(c, p), -1e-12) << p.transpose();
  }
}

TEST(SdfTest, AnOpenComponentIsNeverSkippedNorDecidedByReach) {
  // A closed cube and, beside it, an open plate (one square, two triangles, facing +x). The plate's distance
  // is signed by its pseudo-normal also behind it and beside it, where a closed component would be positive:
  // the union's component skip and BallSdf::atLeast's answer from the triangles within reach hold for closed
  // components only, and the values must stay those of a pass over every triangle of every component.
  TriangleMesh mesh = TriangleMesh::loadObj(writeFile("cube.obj", kUnitCubeObj));
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  for (const Vec3d& v :
       {Vec3d(2.0, -0.5, -0.5), Vec3d(2.0, 0.5, -0.5), Vec3d(2.0, 0.5, 0.5), Vec3d(2.0, -0.5, 0.5)})
    mesh.vertices.push_back(v);
  mesh.triangles.push_back({base, base + 1, base + 2});
  mesh.triangles.push_back({base, base + 2, base + 3});
  auto shared = std::make_shared<const TriangleMesh>(std::move(mesh));
  const std::shared_ptr<const MeshSdfData> data = buildMeshSdfData(*shared);
  ASSERT_EQ(data->components.size(), 2u);
  EXPECT_TRUE(data->closed[0]);
  EXPECT_FALSE(data->closed[1]);
  EXPECT_FALSE(data->allClosed);
  const ColliderDesc c = meshCollider(shared);
  auto overAll = [&](const Vec3d& p) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < data->components.size(); ++k)
      best = std::min(best, componentSdfOverAll(*shared, *data, k, p));
    return best;
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 3.5);
  int negativeBesideThePlate = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3d p(u(rng), 0.6 * u(rng) - 0.5, 0.6 * u(rng) - 0.5);
    const double exact = overAll(p);
    ASSERT_EQ(signedDistanceLocal(c, p), exact) << p.transpose();
    negativeBesideThePlate += exact < 0.0 && p.x() > 0.5;
  }
  EXPECT_GT(negativeBesideThePlate, 10);
  // A parent in front of the plate and beside it, children around it: those behind the plate's plane are
  // negative there although no triangle is near (an open component's sign is not continuous), which the
  // answer from the triangles within reach alone would take for outside.
  const Vec3d centre(2.5, 2.0, 0.0);
  const BallSdf ball(c, centre);
  ASSERT_GT(ball.atCentre(), 0.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int behind = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3d q = centre + Vec3d(unit(rng), unit(rng), unit(rng));
    const double exact = overAll(q);
    behind += exact < 0.0;
    for (const double cl : {0.05, 0.2, 0.6}) {
      ASSERT_EQ(ball.atLeast(q, cl), exact >= cl) << q.transpose() << " clearance " << cl;
    }
  }
  EXPECT_GT(behind, 50);
}

// --- the propeller asset
// ------------------------------------------------------------------------------------------

const std::string kPropellerPath = std::string(FP_SOURCE_DIR) + "/assets/meshes/propeller.obj";

TEST(PropellerTest, ClosedOutwardUnitDiameter) {
  const TriangleMesh m = TriangleMesh::loadObj(kPropellerPath);
  EXPECT_LT(m.triangles.size(), 2000u);
  // Closed and consistently oriented: every directed edge once, and its reverse once.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k)
      ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [e, count] : directed) {
    ASSERT_EQ(count, 1) << e.first << "-" << e.second;
    ASSERT_EQ(directed.count({e.second, e.first}), 1u) << e.first << "-" << e.second;
  }
  double volume = 0.0;
  for (const auto& t : m.triangles) {
    volume += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
  }
  EXPECT_GT(volume, 0.0);
  double tip = 0.0;
  for (const Vec3d& v : m.vertices)
    tip = std::max(tip, std::hypot(v.x(), v.y()));
  EXPECT_NEAR(tip, 0.5, 1e-3);
  const Aabb b = m.bounds();
  EXPECT_NEAR(b.min().z(), -0.08, 0.01);  // the hub is the longest part along the axis
  EXPECT_NEAR(b.max().z(), 0.08, 0.01);
}

TEST(PropellerTest, SamplesOnSurfaceAndSigns) {
  auto mesh = std::make_shared<const TriangleMesh>(TriangleMesh::loadObj(kPropellerPath));
  const ColliderDesc c = meshCollider(mesh);
  const double spacing = 0.02;
  const std::vector<Vec3d> points = sampleColliderLocal(c, spacing);
  ASSERT_GT(points.size(), 100u);
  for (const Vec3d& p : points)
    ASSERT_LT(std::abs(signedDistanceLocal(c, p)), 1e-6) << p.transpose();
  EXPECT_GE(nearestNeighbourRange(points).first, 0.5 * spacing * (1.0 - 1e-9));
  EXPECT_LT(signedDistanceLocal(c, Vec3d(0, 0, 0)), -0.05);           // hub centre
  EXPECT_LT(signedDistanceLocal(c, Vec3d(0.07, 0, 0)), -0.005);       // blade root inside the hub
  EXPECT_LT(signedDistanceLocal(c, Vec3d(0.3, 0, 0)), -0.005);        // mid-span of the first blade
  EXPECT_NEAR(signedDistanceLocal(c, Vec3d(0, 0, 0.3)), 0.22, 1e-9);  // above the hub cap
  EXPECT_GT(signedDistanceLocal(c, Vec3d(0.3, 0, 0.1)), 0.02);        // above the blade
  EXPECT_GT(signedDistanceLocal(c, Vec3d(0.6, 0, 0)), 0.09);          // beyond the tip
}

// Ericson, Real-Time Collision Detection 5.1.5: the point of triangle abc closest to p, written here apart
// from the library's so that the check below does not test the code with itself.
Vec3d referenceClosest(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0)
    return a;
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3)
    return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
    return a + d1 / (d1 - d3) * ab;
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6)
    return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
    return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

TEST(PropellerTest, PrunedDistanceEqualsTheDistanceOverAllTriangles) {
  // The mesh distance walks a bounding-box tree and skips the boxes farther than the nearest triangle so far:
  // the magnitude of each component's distance must still be the distance to the nearest of all its
  // triangles, near the blades (where many triangles compete) and away from them, and the signed value the
  // one a pass over every triangle gives, bit for bit (also on the mesh's corners and edges, where several
  // triangles share the closest point and the sign comes from their pseudo-normal).
  auto mesh = std::make_shared<const TriangleMesh>(TriangleMesh::loadObj(kPropellerPath));
  const ColliderDesc c = meshCollider(mesh);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  std::uniform_real_distribution<double> nearSurface(-0.02, 0.02);
  const std::vector<Vec3d> surface = sampleColliderLocal(c, 0.05);
  std::vector<Vec3d> points;
  for (int i = 0; i < 400; ++i)
    points.emplace_back(u(rng), u(rng), 0.3 * u(rng));
  for (std::size_t i = 0; i < surface.size(); i += 3)
    points.push_back(surface[i] + Vec3d(nearSurface(rng), nearSurface(rng), nearSurface(rng)));
  ASSERT_GT(points.size(), 500u);
  const std::shared_ptr<const MeshSdfData> data = buildMeshSdfData(*mesh);
  ASSERT_GT(data->components.size(), 1u);  // hub and blades: overlapping closed components
  int outside = 0;
  for (const Vec3d& p : points) {
    for (std::size_t k = 0; k < data->components.size(); ++k) {
      double best = std::numeric_limits<double>::infinity();
      for (std::uint32_t tri : data->components[k]) {
        const auto& t = mesh->triangles[tri];
        const Vec3d q = referenceClosest(p, mesh->vertices[t[0]], mesh->vertices[t[1]], mesh->vertices[t[2]]);
        best = std::min(best, (q - p).norm());
      }
      const double tree = componentSdf(*mesh, *data, k, p);
      ASSERT_NEAR(std::abs(tree), best, 1e-12) << "component " << k << " at " << p.transpose();
      ASSERT_EQ(tree, componentSdfOverAll(*mesh, *data, k, p))
          << "component " << k << " at " << p.transpose();
    }
    outside += signedDistanceLocal(c, p) > 0.0 ? 1 : 0;
  }
  EXPECT_GT(outside, 300);
  // corners, edge midpoints and points just off them, inside and out
  int inside = 0;
  std::uniform_real_distribution<double> tiny(-1e-4, 1e-4);
  for (std::size_t t = 0; t < mesh->triangles.size(); t += 7) {
    const auto& tri = mesh->triangles[t];
    const Vec3d& a = mesh->vertices[tri[0]];
    const Vec3d& b = mesh->vertices[tri[1]];
    for (const Vec3d& q : {a, Vec3d(0.5 * (a + b)), Vec3d(a + Vec3d(tiny(rng), tiny(rng), tiny(rng))),
                           Vec3d(0.5 * (a + b) + Vec3d(tiny(rng), tiny(rng), tiny(rng)))}) {
      for (std::size_t k = 0; k < data->components.size(); ++k) {
        const double tree = componentSdf(*mesh, *data, k, q);
        ASSERT_EQ(tree, componentSdfOverAll(*mesh, *data, k, q))
            << "component " << k << " at " << q.transpose();
        inside += tree < 0.0 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(inside, 50);
  // a point that is not finite has no distance
  EXPECT_EQ(componentSdf(*mesh, *data, 0, Vec3d(std::nan(""), 0.0, 0.0)),
            std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace fp::sim
