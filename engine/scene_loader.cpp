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
// culprit.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iomanip>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace fp::engine {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

/// Formats a number compactly (0.1 stays "0.1"), for messages.
std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(12) << v;
  return s.str();
}

/// Formats a vector as "[x, y, z]".
std::string fmt(const sim::Vec3d& v) {
  return "[" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + "]";
}

/// Quotes a string the way JSON would, so control characters cannot break the one-line message.
std::string quoted(const std::string& s) {
  return json(s).dump(-1, ' ', false, json::error_handler_t::replace);
}

/// "a number", "an object", ... for "expected X, got Y" messages.
std::string describe(const json& j) {
  switch (j.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::object:
      return "an object";
    case json::value_t::array:
      return "an array";
    case json::value_t::string:
      return "a string";
    case json::value_t::boolean:
      return "a boolean";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float:
      return "a number";
    default:
      return "an unsupported value";
  }
}

/// Path of member `key` of the object at `parent`; keys that are not identifiers use the bracket form.
std::string memberPath(const std::string& parent, const std::string& key) {
  bool identifier = !key.empty() && !std::isdigit(static_cast<unsigned char>(key[0]));
  for (char c : key) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_')
      identifier = false;
  }
  return identifier ? parent + "." + key : parent + "[" + quoted(key) + "]";
}

/// Path of element `index` of the array at `parent`.
std::string indexPath(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

/// Joins names as "a, b or c" for messages.
std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0)
      out += (i + 1 == names.size()) ? " or " : ", ";
    out += names[i];
  }
  return out;
}

/// Levenshtein distance, to suggest the intended key for a typo.
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

/// " (did you mean x?)" when a known name is close to `key`, else empty.
std::string suggestion(const std::string& key, const std::vector<std::string>& known) {
  std::string best;
  std::size_t bestDistance = 3;  // more edits than this is a different word, not a typo
  for (const std::string& k : known) {
    const std::size_t d = editDistance(key, k);
    if (d < bestDistance) {
      bestDistance = d;
      best = k;
    }
  }
  return best.empty() ? std::string() : " (did you mean " + best + "?)";
}

/// Reads one scene; holds the file name and base folder that every message and asset path needs.
class SceneReader {
 public:
  SceneReader(std::string fileName, std::string baseDir)
      : m_fileName(std::move(fileName)), m_baseDir(std::move(baseDir)) {}

  /// Throws InputError "FILE: PATH: message" as a single line.
  [[noreturn]] void fail(const std::string& path, const std::string& message) const {
    std::string line = m_fileName + ": " + path + ": " + message;
    // Messages from other modules (mesh loader, parameter table) could carry a newline; the contract is one
    // line.
    for (char& c : line) {
      if (c == '\n' || c == '\r' || c == '\t')
        c = ' ';
    }
    throw sim::InputError(line);
  }

  /// Parses the text into JSON, reporting syntax errors with line and column and rejecting duplicate keys.
  json parse(const std::string& text) const;

  /// Converts a parsed document into a scene.
  sim::SceneDesc read(const json& root) const;

 private:
  /// Requires an object whose keys are all in `allowed`.
  void expectObject(const json& j, const std::string& path, const std::vector<std::string>& allowed) const;
  /// The member `key` of `obj`, or fails with "missing required key".
  const json& required(const json& obj, const std::string& path, const char* key) const;

  double readNumber(const json& j, const std::string& path) const;
  bool readBool(const json& j, const std::string& path) const;
  std::string readString(const json& j, const std::string& path) const;
  sim::Vec3d readVec3(const json& j, const std::string& path) const;
  /// a number > 0
  double readPositive(const json& j, const std::string& path) const;
  /// an axis-aligned box given by the "min" and "max" members of `obj`, min < max in every component
  sim::Aabb readBox(const json& obj, const std::string& path) const;

  void readParameters(const json& j, const std::string& path, sim::SimParams& params) const;
  sim::FluidBlock readFluidBlock(const json& j, const std::string& path, const sim::Aabb& domain) const;
  sim::ColliderDesc readCollider(const json& j, const std::string& path, std::size_t index) const;
  sim::Quatd readRotation(const json& j, const std::string& path) const;

  std::string m_fileName;
  std::string m_baseDir;
};

/// Line and 1-based column of byte `offset` in `text`.
std::pair<std::size_t, std::size_t> lineColumn(const std::string& text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

json SceneReader::parse(const std::string& text) const {
  // One frame per open object or array, to name the path of a duplicate key (nlohmann silently keeps the last
  // one, which would hide a typo'd edit of a scene).
  struct Frame {
    bool array = false;
    std::size_t index = 0;
    std::string key;
    std::set<std::string> keys;
  };
  std::vector<Frame> stack;
  auto containerPath = [&]() {
    std::string path = "$";
    for (std::size_t i = 0; i + 1 < stack.size(); ++i) {
      path = stack[i].array ? indexPath(path, stack[i].index) : memberPath(path, stack[i].key);
    }
    return path;
  };
  auto elementDone = [&]() {
    if (!stack.empty() && stack.back().array)
      ++stack.back().index;
  };
  const json::parser_callback_t callback = [&](int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        stack.push_back(Frame{});
        break;
      case json::parse_event_t::array_start:
        stack.push_back(Frame{true, 0, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& top = stack.back();
        top.key = parsed.get<std::string>();
        if (!top.keys.insert(top.key).second)
          fail(memberPath(containerPath(), top.key), "duplicate key");
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        elementDone();
        break;
      case json::parse_event_t::value:
        elementDone();
        break;
    }
    return true;
  };

  try {
    return json::parse(text, callback);
  } catch (const json::parse_error& e) {
    // The parser's own line/column points past the token it peeked at (column 0 at a line end); the byte
    // offset of the last character read is exact, so the position is recomputed from it.
    const auto [line, column] = lineColumn(text, e.byte > 0 ? e.byte - 1 : 0);
    std::string what = e.what();
    const std::size_t columnAt = what.find("column ");
    const std::size_t detailAt =
        columnAt == std::string::npos ? std::string::npos : what.find(": ", columnAt);
    if (detailAt != std::string::npos)
      what = what.substr(detailAt + 2);
    std::string message = m_fileName + ": line " + std::to_string(line) + ", column " +
                          std::to_string(column) + ": invalid JSON: " + what;
    for (char& c : message) {
      if (c == '\n' || c == '\r')
        c = ' ';
    }
    throw sim::InputError(message);
  } catch (const json::exception& e) {
    // e.g. "number overflow parsing '1e400'": a number that is not a finite double. The parser gives no
    // position, so the offending literal is located in the text.
    std::string what = e.what();
    const std::size_t bracket = what.find("] ");
    if (bracket != std::string::npos)
      what = what.substr(bracket + 2);
    std::string where;
    const std::size_t open = what.find('\'');
    const std::size_t close = open == std::string::npos ? std::string::npos : what.find('\'', open + 1);
    if (close != std::string::npos) {
      const std::size_t at = text.find(what.substr(open + 1, close - open - 1));
      if (at != std::string::npos) {
        const auto [line, column] = lineColumn(text, at);
        where = "line " + std::to_string(line) + ", column " + std::to_string(column) + ": ";
      }
    }
    throw sim::InputError(m_fileName + ": " + where + "invalid JSON: " + what + " (numbers must be finite)");
  }
}

void SceneReader::expectObject(const json& j, const std::string& path,
                               const std::vector<std::string>& allowed) const {
  if (!j.is_object())
    fail(path, "expected an object, got " + describe(j));
  for (const auto& item : j.items()) {
    bool known = false;
    for (const std::string& a : allowed)
      known = known || a == item.key();
    if (!known) {
      fail(memberPath(path, item.key()),
           "unknown key" + suggestion(item.key(), allowed) + " (allowed: " + joinNames(allowed) + ")");
    }
  }
}

const json& SceneReader::required(const json& obj, const std::string& path, const char* key) const {
  const auto it = obj.find(key);
  if (it == obj.end())
    fail(memberPath(path, key), "missing required key");
  return *it;
}

double SceneReader::readNumber(const json& j, const std::string& path) const {
  if (!j.is_number())
    fail(path, "expected a number, got " + describe(j));
  const double v = j.get<double>();
  if (!std::isfinite(v))
    fail(path, "must be a finite number");
  return v;
}

bool SceneReader::readBool(const json& j, const std::string& path) const {
  if (!j.is_boolean())
    fail(path, "expected a boolean, got " + describe(j));
  return j.get<bool>();
}

std::string SceneReader::readString(const json& j, const std::string& path) const {
  if (!j.is_string())
    fail(path, "expected a string, got " + describe(j));
  return j.get<std::string>();
}

sim::Vec3d SceneReader::readVec3(const json& j, const std::string& path) const {
  if (!j.is_array())
    fail(path, "expected an array of 3 numbers, got " + describe(j));
  if (j.size() != 3)
    fail(path, "expected an array of 3 numbers, got " + std::to_string(j.size()) + " elements");
  sim::Vec3d v;
  for (std::size_t i = 0; i < 3; ++i)
    v[static_cast<Eigen::Index>(i)] = readNumber(j[i], indexPath(path, i));
  return v;
}

double SceneReader::readPositive(const json& j, const std::string& path) const {
  const double v = readNumber(j, path);
  if (!(v > 0.0))
    fail(path, "must be > 0 (got " + fmt(v) + ")");
  return v;
}

sim::Aabb SceneReader::readBox(const json& obj, const std::string& path) const {
  const sim::Vec3d lo = readVec3(required(obj, path, "min"), memberPath(path, "min"));
  const sim::Vec3d hi = readVec3(required(obj, path, "max"), memberPath(path, "max"));
  if (!(lo.array() < hi.array()).all()) {
    fail(path, "min must be < max in every component (got min " + fmt(lo) + ", max " + fmt(hi) + ")");
  }
  return sim::Aabb(lo, hi);
}

void SceneReader::readParameters(const json& j, const std::string& path, sim::SimParams& params) const {
  const sim::ParamTable& table = sim::ParamTable::sim();
  if (!j.is_object())
    fail(path, "expected an object, got " + describe(j));
  for (const auto& item : j.items()) {
    const std::string itemPath = memberPath(path, item.key());
    const sim::ParamInfo* info = table.find(item.key());
    if (!info) {
      std::vector<std::string> known;
      for (const sim::ParamInfo& e : table.entries())
        known.push_back(e.key);
      fail(itemPath,
           "unknown parameter" + suggestion(item.key(), known) + " (known: " + joinNames(known) + ")");
    }
    // the member's type says what JSON value to read; the table's setters check the range
    const std::string error = sim::visit(*info, std::as_const(params), [&](const auto& current) {
      using T = std::decay_t<decltype(current)>;
      if constexpr (std::is_same_v<T, std::array<double, 3>>) {
        const sim::Vec3d v = readVec3(item.value(), itemPath);
        return sim::ParamTable::setVec3(params, *info, {v.x(), v.y(), v.z()});
      } else if constexpr (std::is_same_v<T, bool>) {
        return sim::ParamTable::setScalar(params, *info, readBool(item.value(), itemPath) ? 1.0 : 0.0);
      } else if constexpr (std::is_same_v<T, sim::Choice>) {
        return sim::ParamTable::setChoice(params, *info, readString(item.value(), itemPath));
      } else {
        return sim::ParamTable::setScalar(params, *info, readNumber(item.value(), itemPath));
      }
    });
    if (!error.empty())
      fail(itemPath, error);
  }
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
  const std::vector<std::string> shapeKeys = {"container",   "half_extents", "radius",
                                              "half_length", "file",         "scale"};
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
      {"box", sim::ShapeType::Box, {"container", "half_extents"}},
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
    if (key == "container")
      fail(memberPath(path, key), "only a box can be a container (shape is " + shapeName + ")");
    fail(memberPath(path, key),
         "not used by a " + shapeName + " collider (allowed: " + joinNames(spec->keys) + ")");
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

  scene.name = fs::path(m_fileName).stem().string();
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
    readParameters(root["parameters"], "$.parameters", scene.params);
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
  std::error_code ec;
  std::ifstream in(path, std::ios::binary);
  // A directory opens as a stream on Linux but cannot be read; report it like a missing file.
  if (!in || fs::is_directory(path, ec))
    throw sim::InputError(path + ": cannot open scene file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
    throw sim::InputError(path + ": cannot open scene file");
  return parseScene(text.str(), path, fs::path(path).parent_path().string());
}

}  // namespace fp::engine
