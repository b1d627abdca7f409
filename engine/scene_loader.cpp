#include "engine/scene_loader.h"

// Scene file format (JSON; also documented in assets/scenes/README.md). Lengths in metres, times in seconds.
//
// {
//   "name": "dam break",                 // string, optional (default: the file stem)
//   "description": "...",                // string, optional, ignored by the simulation
//   "domain": {"min": [x,y,z], "max": [x,y,z]},   // required; min < max in every component
//   "sim_time": 2.0,                     // optional, (0, 1e4] s (default 2)
//   "frame_rate": 60,                    // optional, [1, 1000] frames per simulated second (default 60)
//   "mode": "fluidplaying",              // optional: uniform-low | uniform-high | surface | fluidplaying
//                                        //   (default uniform-high: every particle at particle_radius)
//   "parameters": {"<key>": value, ...}, // optional; keys and ranges from sim::ParamTable (sim/params.cpp):
//                                        //   numbers, booleans for Bool parameters, 3-arrays for Vec3 ones
//   "fluid": [                           // required, at least one block, each inside the domain
//     {"min": [..], "max": [..], "velocity": [..]}   // velocity optional (default 0)
//   ],
//   "colliders": [                       // optional
//     {
//       "name": "tank",                  // optional (default: shape and index)
//       "shape": "box" | "sphere" | "capsule" | "mesh",   // required
//       "container": true,               // box only, optional: the fluid is inside the box
//       "headroom": 0.28,                // container only, optional, >= 0: walls and lid raised (default 0)
//       "half_extents": [..],            // box, required, each > 0
//       "radius": 0.1,                   // sphere and capsule, required, > 0
//       "half_length": 0.2,              // capsule, required, >= 0 (cap centres at local y = +-half_length)
//       "file": "../meshes/a.obj",       // mesh, required, relative to the scene file's folder
//       "scale": 0.3,                    // mesh, optional, > 0 (default 1)
//       "position": [..],                // optional pose (default origin)
//       "rotation": {"axis": [..], "angle_deg": 0},  // optional; axis non-zero, both keys required
//       "linear_velocity": [..],         // optional [m/s]
//       "angular_velocity": [..],        // optional, world frame, about `position` [rad/s]
//       "driven": false                  // optional: the pose is set from outside every step
//     }
//   ]
// }
//
// Unknown keys (anywhere), duplicate keys, wrong types, out-of-range values and missing required keys are
// errors. Every error is one line: "FILE: $.json.path: what is wrong", so that a user can go straight to the
// culprit. The strict reading itself (syntax, duplicates, types, paths) is engine/json_reader's; this file is
// the scene schema.

#include <filesystem>
#include <memory>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/json_reader.h"

namespace fp::engine {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string fmt(double v) {
  return formatJsonNumber(v);
}
std::string fmt(const sim::Vec3d& v) {
  return formatJsonVec3(v);
}

/// Reads one scene: the schema over the strict reader; holds the base folder of relative asset paths.
class SceneReader : public JsonReader {
 public:
  SceneReader(std::string fileName, std::string baseDir)
      : JsonReader(std::move(fileName)), m_baseDir(std::move(baseDir)) {}

  /// Converts a parsed document into a scene.
  sim::SceneDesc read(const json& root) const;

 private:
  /// an axis-aligned box given by the "min" and "max" members of `obj`, min < max in every component
  sim::Aabb readBox(const json& obj, const std::string& path) const;
  sim::FluidBlock readFluidBlock(const json& j, const std::string& path, const sim::Aabb& domain) const;
  sim::ColliderDesc readCollider(const json& j, const std::string& path, std::size_t index) const;
  sim::Quatd readRotation(const json& j, const std::string& path) const;

  std::string m_baseDir;
};

sim::Aabb SceneReader::readBox(const json& obj, const std::string& path) const {
  const sim::Vec3d lo = readVec3(required(obj, path, "min"), memberPath(path, "min"));
  const sim::Vec3d hi = readVec3(required(obj, path, "max"), memberPath(path, "max"));
  if (!(lo.array() < hi.array()).all()) {
    fail(path, "min must be < max in every component (got min " + fmt(lo) + ", max " + fmt(hi) + ")");
  }
  return sim::Aabb(lo, hi);
}

sim::FluidBlock SceneReader::readFluidBlock(const json& j, const std::string& path,
                                            const sim::Aabb& domain) const {
  expectObject(j, path, {"min", "max", "velocity"});
  sim::FluidBlock block;
  block.box = readBox(j, path);
  if (j.contains("velocity"))
    block.velocity = readVec3(j["velocity"], memberPath(path, "velocity"));
  if (!domain.contains(block.box)) {
    fail(path, "block min " + fmt(block.box.min()) + ", max " + fmt(block.box.max()) +
                   " is not inside the domain min " + fmt(domain.min()) + ", max " + fmt(domain.max()));
  }
  return block;
}

sim::Quatd SceneReader::readRotation(const json& j, const std::string& path) const {
  expectObject(j, path, {"axis", "angle_deg"});
  const std::string axisPath = memberPath(path, "axis");
  const sim::Vec3d axis = readVec3(required(j, path, "axis"), axisPath);
  const double angleDeg = readNumber(required(j, path, "angle_deg"), memberPath(path, "angle_deg"));
  if (!(axis.norm() > 0.0))
    fail(axisPath, "must be non-zero (got " + fmt(axis) + ")");
  sim::Quatd q(Eigen::AngleAxisd(angleDeg * sim::kPi / 180.0, axis.normalized()));
  q.normalize();
  return q;
}

sim::ColliderDesc SceneReader::readCollider(const json& j, const std::string& path, std::size_t index) const {
  const std::vector<std::string> common = {"name",   "shape",           "position",        "rotation",
                                           "driven", "linear_velocity", "angular_velocity"};
  const std::vector<std::string> shapeKeys = {"container",   "headroom", "half_extents", "radius",
                                              "half_length", "file",     "scale"};
  std::vector<std::string> allowed = common;
  allowed.insert(allowed.end(), shapeKeys.begin(), shapeKeys.end());
  expectObject(j, path, allowed);

  // Shape first: it decides which of the shape keys belong here.
  struct ShapeSpec {
    const char* name;
    sim::ShapeType type;
    std::vector<std::string> keys;
  };
  const std::vector<ShapeSpec> shapes = {
      {"box", sim::ShapeType::Box, {"container", "headroom", "half_extents"}},
      {"sphere", sim::ShapeType::Sphere, {"radius"}},
      {"capsule", sim::ShapeType::Capsule, {"radius", "half_length"}},
      {"mesh", sim::ShapeType::Mesh, {"file", "scale"}},
  };
  const std::string shapePath = memberPath(path, "shape");
  const std::string shapeName = readString(required(j, path, "shape"), shapePath);
  const ShapeSpec* spec = nullptr;
  for (const ShapeSpec& s : shapes) {
    if (shapeName == s.name)
      spec = &s;
  }
  if (!spec)
    fail(shapePath, "unknown shape " + quoted(shapeName) + " (expected box, sphere, capsule or mesh)");
  for (const std::string& key : shapeKeys) {
    if (!j.contains(key))
      continue;
    bool used = false;
    for (const std::string& k : spec->keys)
      used = used || k == key;
    if (used)
      continue;
    if (key == "container" || key == "headroom")
      fail(memberPath(path, key), "only a box can be a container (shape is " + shapeName + ")");
    fail(memberPath(path, key),
         "not used by a " + shapeName + " collider (allowed: " + sim::joinNames(spec->keys) + ")");
  }

  sim::ColliderDesc c;
  c.shape = spec->type;
  c.name = j.contains("name") ? readString(j["name"], memberPath(path, "name"))
                              : shapeName + " " + std::to_string(index);
  switch (c.shape) {
    case sim::ShapeType::Box: {
      const std::string hePath = memberPath(path, "half_extents");
      c.halfExtents = readVec3(required(j, path, "half_extents"), hePath);
      for (std::size_t i = 0; i < 3; ++i)
        readPositive(j["half_extents"][i], indexPath(hePath, i));
      if (j.contains("container"))
        c.container = readBool(j["container"], memberPath(path, "container"));
      if (j.contains("headroom")) {
        const std::string hrPath = memberPath(path, "headroom");
        if (!c.container)
          fail(hrPath, "only a container has headroom (set \"container\": true)");
        c.headroom = readNumber(j["headroom"], hrPath);
        if (c.headroom < 0.0)
          fail(hrPath, "must be >= 0 (got " + fmt(c.headroom) + ")");
      }
      break;
    }
    case sim::ShapeType::Sphere:
      c.radius = readPositive(required(j, path, "radius"), memberPath(path, "radius"));
      break;
    case sim::ShapeType::Capsule: {
      c.radius = readPositive(required(j, path, "radius"), memberPath(path, "radius"));
      const std::string hlPath = memberPath(path, "half_length");
      c.halfLength = readNumber(required(j, path, "half_length"), hlPath);
      if (c.halfLength < 0.0)
        fail(hlPath, "must be >= 0 (got " + fmt(c.halfLength) + ")");
      break;
    }
    case sim::ShapeType::Mesh: {
      const std::string filePath = memberPath(path, "file");
      const std::string file = readString(required(j, path, "file"), filePath);
      if (file.empty())
        fail(filePath, "must not be empty");
      const double scale = j.contains("scale") ? readPositive(j["scale"], memberPath(path, "scale")) : 1.0;
      // Relative to the scene file, so that a scene folder can be moved or run from any working directory.
      fs::path meshPath(file);
      if (meshPath.is_relative() && !m_baseDir.empty())
        meshPath = fs::path(m_baseDir) / meshPath;
      try {
        sim::TriangleMesh mesh = sim::TriangleMesh::loadObj(meshPath.lexically_normal().string());
        if (scale != 1.0)
          mesh.scale(scale);
        c.mesh = std::make_shared<const sim::TriangleMesh>(std::move(mesh));
      } catch (const std::exception& e) {
        fail(filePath, e.what());
      }
      break;
    }
  }

  if (j.contains("position"))
    c.position = readVec3(j["position"], memberPath(path, "position"));
  if (j.contains("rotation"))
    c.orientation = readRotation(j["rotation"], memberPath(path, "rotation"));
  if (j.contains("linear_velocity")) {
    c.linearVelocity = readVec3(j["linear_velocity"], memberPath(path, "linear_velocity"));
  }
  if (j.contains("angular_velocity")) {
    c.angularVelocity = readVec3(j["angular_velocity"], memberPath(path, "angular_velocity"));
  }
  if (j.contains("driven"))
    c.driven = readBool(j["driven"], memberPath(path, "driven"));
  return c;
}

sim::SceneDesc SceneReader::read(const json& root) const {
  const std::string path = "$";
  expectObject(root, path,
               {"name", "description", "domain", "sim_time", "frame_rate", "mode", "parameters", "fluid",
                "colliders"});
  sim::SceneDesc scene;

  scene.name = fs::path(fileName()).stem().string();
  if (scene.name.empty())
    scene.name = "scene";
  if (root.contains("name"))
    scene.name = readString(root["name"], "$.name");
  if (root.contains("description"))
    readString(root["description"], "$.description");

  const json& domain = required(root, path, "domain");
  expectObject(domain, "$.domain", {"min", "max"});
  scene.domain = readBox(domain, "$.domain");

  if (root.contains("sim_time")) {
    scene.simTime = readNumber(root["sim_time"], "$.sim_time");
    if (!(scene.simTime > 0.0 && scene.simTime <= 1e4)) {
      fail("$.sim_time", "must be in (0, 10000] (got " + fmt(scene.simTime) + ")");
    }
  }
  if (root.contains("frame_rate")) {
    scene.frameRate = readNumber(root["frame_rate"], "$.frame_rate");
    if (!(scene.frameRate >= 1.0 && scene.frameRate <= 1000.0)) {
      fail("$.frame_rate", "must be in [1, 1000] (got " + fmt(scene.frameRate) + ")");
    }
  }

  if (root.contains("mode")) {
    const std::string mode = readString(root["mode"], "$.mode");
    const auto parsed = sim::parseMode(mode);
    if (!parsed)
      fail("$.mode", "expected one of " + std::string(sim::modeNames()) + ", got '" + mode + "'");
    scene.mode = *parsed;
  }

  if (root.contains("parameters"))
    readTable(root["parameters"], "$.parameters", sim::ParamTable::sim(), scene.params);
  // Relations between parameters (dt_min <= dt_max, ...) are checked once all of them are set.
  const std::string relation = sim::ParamTable::validate(scene.params);
  if (!relation.empty())
    fail(root.contains("parameters") ? "$.parameters" : "$", relation);

  const json& fluid = required(root, path, "fluid");
  if (!fluid.is_array())
    fail("$.fluid", "expected an array, got " + describe(fluid));
  if (fluid.empty())
    fail("$.fluid", "must contain at least one block");
  for (std::size_t i = 0; i < fluid.size(); ++i) {
    scene.fluid.push_back(readFluidBlock(fluid[i], indexPath("$.fluid", i), scene.domain));
  }

  if (root.contains("colliders")) {
    const json& colliders = root["colliders"];
    if (!colliders.is_array())
      fail("$.colliders", "expected an array, got " + describe(colliders));
    for (std::size_t i = 0; i < colliders.size(); ++i) {
      scene.colliders.push_back(readCollider(colliders[i], indexPath("$.colliders", i), i));
    }
  }
  return scene;
}

}  // namespace

sim::SceneDesc parseScene(const std::string& jsonText, const std::string& fileName,
                          const std::string& baseDir) {
  const SceneReader reader(fileName, baseDir);
  return reader.read(reader.parse(jsonText));
}

sim::SceneDesc loadScene(const std::string& path) {
  const std::string text = readTextFile(path, "scene file");
  return parseScene(text, path, fs::path(path).parent_path().string());
}

}  // namespace fp::engine
