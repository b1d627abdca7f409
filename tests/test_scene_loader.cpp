// Scene loading: every shipped scene loads with the intended values, and every kind of bad input is rejected
// with one line that names the file and the exact JSON path. Presets go through the same strict reader.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "engine/json_reader.h"
#include "engine/presets.h"
#include "engine/scene_loader.h"
#include "sim/boundary_sampling.h"
#include "sim/signed_distance.h"
#include "tests/temp_path.h"

namespace fp::engine {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string scenePath(const std::string& name) {
  return std::string(FP_SOURCE_DIR) + "/assets/scenes/" + name;
}

/// A small valid scene that each error test breaks in one place.
json validScene() {
  return json::parse(R"({
    "name": "test",
    "domain": {"min": [-1, -1, -1], "max": [1, 1, 1]},
    "parameters": {"particle_radius": 0.05},
    "fluid": [{"min": [-0.5, -0.5, -0.5], "max": [0.0, 0.0, 0.0]}],
    "colliders": [
      {"shape": "box", "container": true, "half_extents": [0.9, 0.9, 0.9]},
      {"shape": "sphere", "radius": 0.1, "position": [0.5, 0.5, 0.5]}
    ]
  })");
}

/// Parses `text` as "bad.json", expects an InputError and returns its message.
std::string errorOf(const std::string& text) {
  try {
    parseScene(text, "bad.json", "");
  } catch (const sim::InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    return message;
  }
  ADD_FAILURE() << "no error for: " << text;
  return {};
}

std::string errorOf(const json& scene) {
  return errorOf(scene.dump(2));
}

/// Message starts with "bad.json: PATH: ".
::testing::AssertionResult namesPath(const std::string& message, const std::string& path) {
  const std::string prefix = "bad.json: " + path + ": ";
  if (message.rfind(prefix, 0) == 0)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "expected prefix \"" << prefix << "\" in: " << message;
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(SceneLoaderTest, ValidSceneParses) {
  const sim::SceneDesc scene = parseScene(validScene().dump(), "dir/valid.json", "");
  EXPECT_EQ(scene.name, "test");
  EXPECT_EQ(scene.fluid.size(), 1u);
  ASSERT_EQ(scene.colliders.size(), 2u);
  EXPECT_EQ(scene.colliders[1].shape, sim::ShapeType::Sphere);
  EXPECT_DOUBLE_EQ(scene.colliders[1].radius, 0.1);
  EXPECT_DOUBLE_EQ(scene.params.particleRadius, 0.05);
}

TEST(SceneLoaderTest, NameDefaultsToFileStem) {
  json s = validScene();
  s.erase("name");
  EXPECT_EQ(parseScene(s.dump(), "scenes/my_scene.json", "").name, "my_scene");
}

TEST(SceneLoaderTest, DamBreakHasReferenceValues) {
  const sim::SceneDesc scene = loadScene(scenePath("dam_break.json"));
  EXPECT_EQ(scene.name, "dam break");
  EXPECT_DOUBLE_EQ(scene.simTime, 2.0);
  EXPECT_DOUBLE_EQ(scene.frameRate, 60.0);

  ASSERT_EQ(scene.fluid.size(), 1u);
  EXPECT_TRUE(scene.fluid[0].box.min().isApprox(sim::Vec3d(-1.95, 0.05, -0.5)));
  EXPECT_TRUE(scene.fluid[0].box.max().isApprox(sim::Vec3d(-0.95, 1.05, 0.5)));
  EXPECT_TRUE(scene.fluid[0].velocity.isZero());

  ASSERT_EQ(scene.colliders.size(), 1u);
  const sim::ColliderDesc& tank = scene.colliders[0];
  EXPECT_EQ(tank.shape, sim::ShapeType::Box);
  EXPECT_TRUE(tank.container);
  EXPECT_FALSE(tank.kinematic());
  EXPECT_TRUE(tank.halfExtents.isApprox(sim::Vec3d(2.0, 1.5, 0.75)));
  EXPECT_TRUE(tank.position.isApprox(sim::Vec3d(0.0, 1.5, 0.0)));
  EXPECT_TRUE(tank.orientation.isApprox(sim::Quatd::Identity()));

  // Domain: the container (x [-2, 2], y [0, 3], z [-0.75, 0.75]) plus a 0.1 m margin.
  EXPECT_TRUE(scene.domain.min().isApprox(sim::Vec3d(-2.1, -0.1, -0.85)));
  EXPECT_TRUE(scene.domain.max().isApprox(sim::Vec3d(2.1, 3.1, 0.85)));

  const sim::SimParams& p = scene.params;
  EXPECT_DOUBLE_EQ(p.particleRadius, 0.025);
  // the reference scene's viscosity: SPlisHSPlasH's Viscosity_Standard with 0.01 m^2/s, no XSPH (issue #12)
  EXPECT_DOUBLE_EQ(p.viscosity, 0.0);
  EXPECT_DOUBLE_EQ(p.laminarViscosity, 0.01);
  EXPECT_DOUBLE_EQ(p.cflFactor, 0.4);
  EXPECT_DOUBLE_EQ(p.dtMax, 0.005);
  EXPECT_DOUBLE_EQ(p.densityTolerance, 0.05);
  EXPECT_DOUBLE_EQ(p.divergenceTolerance, 0.1);
  EXPECT_EQ(p.minIterations, 2);

  // The block is a 1 m cube: 20 lattice spacings of 2r per side.
  EXPECT_TRUE(scene.fluid[0].box.sizes().isApprox(sim::Vec3d::Constant(20.0 * 2.0 * p.particleRadius)));
}

TEST(SceneLoaderTest, DamBreakHiresDiffersOnlyInRadius) {
  const sim::SceneDesc lo = loadScene(scenePath("dam_break.json"));
  const sim::SceneDesc hi = loadScene(scenePath("dam_break_hires.json"));
  EXPECT_DOUBLE_EQ(hi.params.particleRadius, 0.0105);
  EXPECT_DOUBLE_EQ(hi.params.viscosity, lo.params.viscosity);
  EXPECT_DOUBLE_EQ(hi.params.laminarViscosity, lo.params.laminarViscosity);
  EXPECT_DOUBLE_EQ(hi.params.cflFactor, lo.params.cflFactor);
  EXPECT_DOUBLE_EQ(hi.params.dtMax, lo.params.dtMax);
  EXPECT_DOUBLE_EQ(hi.params.densityTolerance, lo.params.densityTolerance);
  EXPECT_DOUBLE_EQ(hi.params.divergenceTolerance, lo.params.divergenceTolerance);
  EXPECT_EQ(hi.params.minIterations, lo.params.minIterations);
  EXPECT_DOUBLE_EQ(hi.simTime, lo.simTime);
  EXPECT_TRUE(hi.domain.isApprox(lo.domain));
  ASSERT_EQ(hi.fluid.size(), 1u);
  EXPECT_TRUE(hi.fluid[0].box.isApprox(lo.fluid[0].box));
  ASSERT_EQ(hi.colliders.size(), 1u);
  EXPECT_TRUE(hi.colliders[0].halfExtents.isApprox(lo.colliders[0].halfExtents));
  EXPECT_TRUE(hi.colliders[0].position.isApprox(lo.colliders[0].position));
  EXPECT_EQ(hi.colliders[0].container, lo.colliders[0].container);
}

TEST(SceneLoaderTest, TankRestLoads) {
  const sim::SceneDesc scene = loadScene(scenePath("tank_rest.json"));
  EXPECT_DOUBLE_EQ(scene.params.particleRadius, 0.0098039);
  EXPECT_DOUBLE_EQ(scene.simTime, 2.0);
  ASSERT_EQ(scene.colliders.size(), 1u);
  const sim::ColliderDesc& tank = scene.colliders[0];
  EXPECT_TRUE(tank.container);
  EXPECT_TRUE(tank.halfExtents.isApprox(sim::Vec3d(0.2, 0.2, 0.2)));
  EXPECT_NEAR(tank.position.y() - tank.halfExtents.y(), 0.0, 1e-12);  // floor at y = 0
  ASSERT_EQ(scene.fluid.size(), 1u);
  EXPECT_NEAR(scene.fluid[0].box.max().y(), 0.3, 1e-12);
}

TEST(SceneLoaderTest, TinyDamBreakLoads) {
  const sim::SceneDesc scene = loadScene(scenePath("tiny_dam_break.json"));
  EXPECT_DOUBLE_EQ(scene.params.particleRadius, 0.01);
  EXPECT_DOUBLE_EQ(scene.simTime, 1.0);
  ASSERT_EQ(scene.colliders.size(), 1u);
  const sim::ColliderDesc& tank = scene.colliders[0];
  EXPECT_TRUE(tank.halfExtents.isApprox(sim::Vec3d(0.2, 0.15, 0.1)));
  ASSERT_EQ(scene.fluid.size(), 1u);
  // The water stays inside the tank, 1 mm from its walls.
  const sim::Aabb inner(tank.position - tank.halfExtents, tank.position + tank.halfExtents);
  EXPECT_TRUE(inner.contains(scene.fluid[0].box));
  EXPECT_NEAR(scene.fluid[0].box.min().x() - inner.min().x(), 0.001, 1e-9);
}

TEST(SceneLoaderTest, PropellerLoads) {
  if (!fs::exists(std::string(FP_SOURCE_DIR) + "/assets/meshes/propeller.obj")) {
    GTEST_SKIP() << "assets/meshes/propeller.obj is not there yet";
  }
  const sim::SceneDesc scene = loadScene(scenePath("propeller.json"));
  EXPECT_DOUBLE_EQ(scene.params.particleRadius, 0.0088);
  EXPECT_DOUBLE_EQ(scene.simTime, 4.0);
  ASSERT_EQ(scene.colliders.size(), 2u);
  const sim::ColliderDesc& prop = scene.colliders[1];
  EXPECT_EQ(prop.shape, sim::ShapeType::Mesh);
  ASSERT_TRUE(prop.mesh);
  EXPECT_FALSE(prop.mesh->triangles.empty());
  EXPECT_TRUE(prop.kinematic());
  EXPECT_TRUE(prop.angularVelocity.isApprox(sim::Vec3d(12.0, 0.0, 0.0)));
  // The local spin axis +z points along world x.
  EXPECT_TRUE((prop.orientation * sim::Vec3d::UnitZ()).isApprox(sim::Vec3d::UnitX(), 1e-12));
  // Unit diameter scaled by 0.28: the blade tips reach 0.14 m from the local spin axis.
  double tipRadius = 0.0;
  for (const sim::Vec3d& v : prop.mesh->vertices)
    tipRadius = std::max(tipRadius, std::hypot(v.x(), v.y()));
  EXPECT_NEAR(tipRadius, 0.14, 0.005);
}

TEST(SceneLoaderTest, MeshPathIsRelativeToSceneAndScaled) {
  const fs::path dir = fs::temp_directory_path() / ("fp_scene_loader_" + std::to_string(::getpid()));
  fs::create_directories(dir / "scenes");
  fs::create_directories(dir / "meshes");
  {
    std::ofstream obj(dir / "meshes" / "tet.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  json s = validScene();
  s["colliders"] = json::array({{{"shape", "mesh"}, {"file", "../meshes/tet.obj"}, {"scale", 2.0}}});
  const std::string scenePathStr = (dir / "scenes" / "mesh.json").string();
  {
    std::ofstream out(scenePathStr);
    out << s.dump(2);
  }
  const sim::SceneDesc scene = loadScene(scenePathStr);
  fs::remove_all(dir);
  ASSERT_EQ(scene.colliders.size(), 1u);
  ASSERT_TRUE(scene.colliders[0].mesh);
  EXPECT_EQ(scene.colliders[0].mesh->triangles.size(), 4u);
  EXPECT_TRUE(scene.colliders[0].mesh->bounds().max().isApprox(sim::Vec3d(2.0, 2.0, 2.0)));
}

TEST(SceneLoaderTest, ParameterKindsAreSet) {
  json s = validScene();
  s["parameters"]["gravity"] = {0.0, -1.0, 0.5};
  s["parameters"]["warm_start"] = false;
  s["parameters"]["max_iterations"] = 50;
  const sim::SceneDesc scene = parseScene(s.dump(), "x.json", "");
  EXPECT_DOUBLE_EQ(scene.params.gravity[1], -1.0);
  EXPECT_DOUBLE_EQ(scene.params.gravity[2], 0.5);
  EXPECT_FALSE(scene.params.warmStart);
  EXPECT_EQ(scene.params.maxIterations, 50);
}

TEST(SceneLoaderTest, InvalidSyntaxReportsLineAndColumn) {
  const std::string text = "{\n  \"name\": \"x\",\n  \"domain\" {}\n}\n";
  const std::string message = errorOf(text);
  EXPECT_EQ(message.rfind("bad.json: line 3, column ", 0), 0u) << message;
  EXPECT_TRUE(contains(message, "invalid JSON")) << message;
}

TEST(SceneLoaderTest, EmptyTextIsASyntaxError) {
  EXPECT_EQ(errorOf(std::string()).rfind("bad.json: line 1, column 1: invalid JSON", 0), 0u);
}

TEST(SceneLoaderTest, UnknownTopLevelKey) {
  json s = validScene();
  s["gravity"] = {0, -9.81, 0};
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.gravity"));
  EXPECT_TRUE(contains(message, "unknown key")) << message;
}

TEST(SceneLoaderTest, UnknownParameterKeySuggestsTheRightOne) {
  json s = validScene();
  s["parameters"]["partcle_radius"] = 0.01;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.parameters.partcle_radius"));
  EXPECT_TRUE(contains(message, "unknown parameter")) << message;
  EXPECT_TRUE(contains(message, "did you mean particle_radius?")) << message;
}

TEST(SceneLoaderTest, UnknownColliderKey) {
  json s = validScene();
  s["colliders"][1]["colour"] = "red";
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].colour"));
  EXPECT_TRUE(contains(message, "unknown key")) << message;
}

TEST(SceneLoaderTest, KeyOfAnotherShape) {
  json s = validScene();
  s["colliders"][1]["half_extents"] = {1, 1, 1};
  EXPECT_TRUE(namesPath(errorOf(s), "$.colliders[1].half_extents"));
}

TEST(SceneLoaderTest, DuplicateKey) {
  const std::string text = R"({"domain": {"min": [-1, -1, -1], "max": [1, 1, 1]},
    "fluid": [{"min": [0, 0, 0], "max": [0.5, 0.5, 0.5], "min": [0, 0, 0]}]})";
  const std::string message = errorOf(text);
  EXPECT_TRUE(namesPath(message, "$.fluid[0].min"));
  EXPECT_TRUE(contains(message, "duplicate key")) << message;
}

TEST(SceneLoaderTest, WrongType) {
  json s = validScene();
  s["colliders"][1]["radius"] = "0.1";
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].radius"));
  EXPECT_TRUE(contains(message, "expected a number, got a string")) << message;
}

TEST(SceneLoaderTest, WrongTypeInsideVector) {
  json s = validScene();
  s["domain"]["max"][2] = true;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.domain.max[2]"));
  EXPECT_TRUE(contains(message, "expected a number, got a boolean")) << message;
}

TEST(SceneLoaderTest, VectorOfWrongLength) {
  json s = validScene();
  s["colliders"][1]["position"] = {0.0, 1.0};
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].position"));
  EXPECT_TRUE(contains(message, "3 numbers")) << message;
}

TEST(SceneLoaderTest, BooleanParameterNeedsBoolean) {
  json s = validScene();
  s["parameters"]["warm_start"] = 1;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.parameters.warm_start"));
  EXPECT_TRUE(contains(message, "expected a boolean, got a number")) << message;
}

TEST(SceneLoaderTest, OutOfRangeParameter) {
  json s = validScene();
  s["parameters"]["particle_radius"] = -1;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.parameters.particle_radius"));
  EXPECT_TRUE(contains(message, "out of range")) << message;
}

TEST(SceneLoaderTest, NonIntegralIntegerParameter) {
  json s = validScene();
  s["parameters"]["min_iterations"] = 2.5;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.parameters.min_iterations"));
  EXPECT_TRUE(contains(message, "integer")) << message;
}

TEST(SceneLoaderTest, ParameterRelation) {
  json s = validScene();
  s["parameters"]["dt_min"] = 0.004;
  s["parameters"]["dt_max"] = 0.001;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.parameters"));
  EXPECT_TRUE(contains(message, "dt_min")) << message;
}

TEST(SceneLoaderTest, OutOfRangeSceneValue) {
  json s = validScene();
  s["sim_time"] = 0;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.sim_time"));
  EXPECT_TRUE(contains(message, "(0, 10000]")) << message;
}

TEST(SceneLoaderTest, NegativeRadiusNamesValue) {
  json s = validScene();
  s["colliders"][1]["radius"] = -0.1;
  EXPECT_EQ(errorOf(s), "bad.json: $.colliders[1].radius: must be > 0 (got -0.1)");
}

TEST(SceneLoaderTest, MissingDomain) {
  json s = validScene();
  s.erase("domain");
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.domain"));
  EXPECT_TRUE(contains(message, "missing required key")) << message;
}

TEST(SceneLoaderTest, NoFluid) {
  json s = validScene();
  s["fluid"] = json::array();
  EXPECT_TRUE(namesPath(errorOf(s), "$.fluid"));
}

TEST(SceneLoaderTest, FluidBlockOutsideDomain) {
  json s = validScene();
  s["fluid"][0]["max"] = {0.5, 1.5, 0.5};
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.fluid[0]"));
  EXPECT_TRUE(contains(message, "not inside the domain")) << message;
}

TEST(SceneLoaderTest, MinNotBelowMax) {
  json s = validScene();
  s["domain"]["min"][1] = 1.0;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.domain"));
  EXPECT_TRUE(contains(message, "min must be < max")) << message;
}

TEST(SceneLoaderTest, BadShapeName) {
  json s = validScene();
  s["colliders"][0]["shape"] = "cube";
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[0].shape"));
  EXPECT_TRUE(contains(message, "\"cube\"")) << message;
}

TEST(SceneLoaderTest, ContainerOnSphere) {
  json s = validScene();
  s["colliders"][1]["container"] = true;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].container"));
  EXPECT_TRUE(contains(message, "only a box")) << message;
}

TEST(SceneLoaderTest, HeadroomRaisesAContainersWallsAndLid) {
  json s = validScene();
  s["colliders"][0]["headroom"] = 0.3;
  const sim::SceneDesc scene = parseScene(s.dump(2), "scene.json", "");
  const sim::ColliderDesc& tank = scene.colliders[0];
  EXPECT_DOUBLE_EQ(tank.headroom, 0.3);
  // the lid 0.3 above the box's top face (0.9), the floor where it was; inside the raised part is water's
  // side
  double top = -1e9, bottom = 1e9;
  for (const sim::Vec3d& p : sim::sampleColliderLocal(tank, 0.1)) {
    top = std::max(top, p.y());
    bottom = std::min(bottom, p.y());
  }
  EXPECT_DOUBLE_EQ(top, 1.2);
  EXPECT_DOUBLE_EQ(bottom, -0.9);
  EXPECT_NEAR(sim::signedDistanceLocal(tank, sim::Vec3d(0.0, 1.0, 0.0)), 0.2, 1e-12);
  EXPECT_NEAR(sim::signedDistanceLocal(tank, sim::Vec3d(0.0, -0.8, 0.0)), 0.1, 1e-12);
  EXPECT_NEAR(sim::signedDistanceLocal(tank, sim::Vec3d(0.0, 1.3, 0.0)), -0.1, 1e-12);

  s["colliders"][0]["headroom"] = -0.1;
  std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[0].headroom"));
  EXPECT_TRUE(contains(message, "must be >= 0")) << message;
  s["colliders"][0]["headroom"] = 0.1;
  s["colliders"][0]["container"] = false;
  message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[0].headroom"));
  EXPECT_TRUE(contains(message, "only a container")) << message;
  s["colliders"][0]["container"] = true;
  s["colliders"][1]["headroom"] = 0.1;
  message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].headroom"));
  EXPECT_TRUE(contains(message, "only a box")) << message;
}

TEST(SceneLoaderTest, MissingMeshFile) {
  json s = validScene();
  s["colliders"][1] = {{"shape", "mesh"}, {"file", "no_such_mesh.obj"}};
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].file"));
  EXPECT_TRUE(contains(message, "no_such_mesh.obj")) << message;
}

TEST(SceneLoaderTest, ZeroRotationAxis) {
  json s = validScene();
  s["colliders"][1]["rotation"] = {{"axis", {0, 0, 0}}, {"angle_deg", 30}};
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.colliders[1].rotation.axis"));
  EXPECT_TRUE(contains(message, "non-zero")) << message;
}

TEST(SceneLoaderTest, RotationIsApplied) {
  json s = validScene();
  s["colliders"][1]["rotation"] = {{"axis", {0, 0, 2}}, {"angle_deg", 90}};
  const sim::SceneDesc scene = parseScene(s.dump(), "x.json", "");
  EXPECT_TRUE((scene.colliders[1].orientation * sim::Vec3d::UnitX()).isApprox(sim::Vec3d::UnitY(), 1e-12));
}

// JSON cannot carry NaN or infinity; a literal too large for a double is the closest thing and must not pass.
TEST(SceneLoaderTest, NumberTooLargeForDouble) {
  const std::string text = R"({"domain": {"min": [-1, -1, -1], "max": [1, 1e400, 1]}, "fluid": []})";
  const std::string message = errorOf(text);
  EXPECT_EQ(message.rfind("bad.json: line 1, column ", 0), 0u) << message;
  EXPECT_TRUE(contains(message, "1e400")) << message;
}

TEST(SceneLoaderTest, MissingSceneFile) {
  const std::string path = scenePath("no_such_scene.json");
  try {
    loadScene(path);
    FAIL() << "no error";
  } catch (const sim::InputError& e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot open scene file");
  }
}

// Presets are read by the scenes' strict reader: the same duplicate-key, suggestion and path messages.
class PresetFileTest : public ::testing::Test {
 protected:
  std::string m_path = test::tempPath("preset.json");
  void TearDown() override { fs::remove(m_path); }
  std::string errorOfPreset(const std::string& text) {
    std::ofstream(m_path) << text;
    try {
      loadPreset(m_path, Preset{});
    } catch (const sim::InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
      EXPECT_EQ(message.rfind(m_path + ": ", 0), 0u) << message;
      return message.substr(m_path.size() + 2);
    }
    ADD_FAILURE() << "no error for: " << text;
    return {};
  }
};

TEST_F(PresetFileTest, RoundTripsEveryParameter) {
  Preset p;
  p.mode = sim::AdaptivityMode::Surface;
  p.params.gravity = {0.5, -3.0, 1.0 / 3.0};
  p.params.dtMin = 1.0 / 7.0 * 1e-4;
  p.params.seed = 4294967295u;
  p.params.divergenceSolve = false;
  p.render.view = render::RenderSettings::View::Particles;
  p.render.colorField = render::ColorField::Omega;
  p.render.highlightDuration = 1.25f;
  savePreset(m_path, p);
  const Preset q = loadPreset(m_path, Preset{});
  EXPECT_EQ(q.mode, p.mode);
  for (const sim::ParamInfo& info : sim::ParamTable::sim().entries())
    EXPECT_TRUE(sim::ParamTable::equal(info, p.params, q.params)) << info.key;
  EXPECT_TRUE(render::RenderSettingsTable::get().allEqual(p.render, q.render));
  EXPECT_EQ(q.render.colorField, render::ColorField::Omega);
}

TEST_F(PresetFileTest, KeysLeftOutKeepTheBase) {
  Preset base;
  base.params.viscosity = 0.5;
  std::ofstream(m_path) << R"({"parameters": {"splash_count": 9}})";
  const Preset q = loadPreset(m_path, base);
  EXPECT_EQ(q.params.viscosity, 0.5);
  EXPECT_EQ(q.params.splashCount, 9);
}

TEST_F(PresetFileTest, ErrorsNameThePath) {
  EXPECT_EQ(errorOfPreset(R"({"parameters": {"viscosity": 0.1, "viscosity": 0.2}})"),
            "$.parameters.viscosity: duplicate key");
  const std::string misspelt = errorOfPreset(R"({"parameters": {"surface_distanse_lo": 3}})");
  EXPECT_EQ(misspelt.rfind("$.parameters.surface_distanse_lo: unknown parameter (did you mean "
                           "surface_distance_lo?) (known: particle_radius, ",
                           0),
            0u)
      << misspelt;
  EXPECT_EQ(errorOfPreset(R"({"mdoe": "surface"})").rfind("$.mdoe: unknown key (did you mean mode?)", 0), 0u);
  EXPECT_EQ(errorOfPreset(R"({"parameters": {"split_max_children": 99}})"),
            "$.parameters.split_max_children: split_max_children = 99 is out of range [8, 27]");
  EXPECT_EQ(errorOfPreset(R"({"parameters": {"warm_start": 1}})"),
            "$.parameters.warm_start: expected a boolean, got a number");
  EXPECT_EQ(errorOfPreset(R"({"parameters": {"gravity": [0, "x", 0]}})"),
            "$.parameters.gravity[1]: expected a number, got a string");
  EXPECT_EQ(errorOfPreset(R"({"render": {"veiw": "particles"}})")
                .rfind("$.render.veiw: unknown render setting (did you mean view?) (known: view, ", 0),
            0u);
  EXPECT_EQ(errorOfPreset(R"({"render": {"view": "water"}})"),
            "$.render.view: view: expected fluid or particles, got 'water'");
  EXPECT_EQ(errorOfPreset(R"({"mode": "adaptive"})"),
            "$.mode: expected one of " + std::string(sim::modeNames()) + ", got 'adaptive'");
  EXPECT_EQ(errorOfPreset(R"({"parameters": {"dt_min": 0.01, "dt_max": 0.001}})"),
            "$.parameters: dt_min must not exceed dt_max");
  EXPECT_EQ(errorOfPreset("{\"mode\": }").rfind("line 1, column 10: invalid JSON: ", 0), 0u);
}

// The reader on its own: any table, paths of nested members, suggestions among the allowed keys.
TEST(JsonReaderTest, ReadsATableAndNamesPaths) {
  const JsonReader reader("f.json");
  const nlohmann::json j = reader.parse(R"({"p": {"dt_max": 0.002, "gravity": [0, -1, 0], "seed": 7}})");
  sim::SimParams params;
  reader.readTable(j["p"], "$.p", sim::ParamTable::sim(), params);
  EXPECT_EQ(params.dtMax, 0.002);
  EXPECT_EQ(params.gravity, (std::array<double, 3>{0, -1, 0}));
  EXPECT_EQ(params.seed, 7u);
  EXPECT_EQ(memberPath("$.a", "b c"), "$.a[\"b c\"]");
  EXPECT_EQ(indexPath("$.a", 2), "$.a[2]");
  try {
    reader.expectObject(j, "$", {"q", "r"});
    ADD_FAILURE();
  } catch (const sim::InputError& e) {
    EXPECT_STREQ(e.what(), "f.json: $.p: unknown key (did you mean q?) (allowed: q or r)");
  }
  try {
    reader.parse(R"({"a": [{"b": 1, "b": 2}]})");
    ADD_FAILURE();
  } catch (const sim::InputError& e) {
    EXPECT_STREQ(e.what(), "f.json: $.a[0].b: duplicate key");
  }
}

}  // namespace
}  // namespace fp::engine

namespace fp::engine {

TEST(SceneLoaderTest, ModeDefaultsToUniformHighAndParses) {
  EXPECT_EQ(parseScene(validScene().dump(), "ok.json", "").mode, sim::AdaptivityMode::UniformHigh);
  json s = validScene();
  s["mode"] = "surface";
  EXPECT_EQ(parseScene(s.dump(), "ok.json", "").mode, sim::AdaptivityMode::Surface);
  EXPECT_EQ(loadScene(scenePath("propeller.json")).mode, sim::AdaptivityMode::FluidPlaying);
  EXPECT_EQ(loadScene(scenePath("propeller_hires.json")).params.particleRadius, 0.00538);
}

TEST(SceneLoaderTest, BadModeNamesThePathAndTheChoices) {
  json s = validScene();
  s["mode"] = "adaptive";
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.mode"));
  EXPECT_TRUE(contains(message, "uniform-low, uniform-high, surface, fluidplaying")) << message;
  s["mode"] = 3;
  EXPECT_TRUE(namesPath(errorOf(s), "$.mode"));
}

TEST(SceneLoaderTest, AdaptivityIntervalMustBeOrdered) {
  json s = validScene();
  s["parameters"]["vorticity_lo"] = 40.0;
  s["parameters"]["vorticity_hi"] = 20.0;
  const std::string message = errorOf(s);
  EXPECT_TRUE(namesPath(message, "$.parameters"));
  EXPECT_TRUE(contains(message, "vorticity_lo")) << message;
  s = validScene();
  s["parameters"]["split_max_children"] = 40;
  EXPECT_TRUE(namesPath(errorOf(s), "$.parameters.split_max_children"));
}

}  // namespace fp::engine
