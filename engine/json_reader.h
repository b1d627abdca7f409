#pragma once
/// Strict JSON reading for the project's files (scenes, presets): duplicate keys, unknown keys (with a
/// suggestion for a misspelt one), wrong types and out-of-range table values are rejected, each with one line
/// "FILE: $.json.path: what is wrong" so that a user can go straight to the culprit.

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "sim/param_table.h"
#include "sim/scene.h"

namespace fp::engine {

/// A number as the messages write it: up to 12 significant digits (0.1 stays "0.1").
std::string formatJsonNumber(double v);
/// A vector as "[x, y, z]".
std::string formatJsonVec3(const sim::Vec3d& v);
/// A string quoted as JSON would, so that control characters cannot break a one-line message.
std::string quoted(const std::string& s);
/// "a number", "an object", ... for "expected X, got Y" messages.
std::string describe(const nlohmann::json& j);
/// Path of member `key` of the object at `parent` ($.a.b; keys that are not identifiers as $["a b"]).
std::string memberPath(const std::string& parent, const std::string& key);
/// Path of element `index` of the array at `parent` ($.a[2]).
std::string indexPath(const std::string& parent, std::size_t index);
/// The whole file as text; throws sim::InputError "PATH: cannot open WHAT" (a folder counts as missing).
std::string readTextFile(const std::string& path, const std::string& what);

/// Reads one JSON document strictly; holds the file name that every message starts with.
class JsonReader {
 public:
  using json = nlohmann::json;

  /// `fileName` starts every message
  explicit JsonReader(std::string fileName) : m_fileName(std::move(fileName)) {}
  /// the file name of the messages
  const std::string& fileName() const { return m_fileName; }

  /// Throws sim::InputError "FILE: PATH: message" as a single line.
  [[noreturn]] void fail(const std::string& path, const std::string& message) const;

  /// Parses the text, reporting syntax errors with line and column ("FILE: line L, column C: invalid JSON:
  /// ...") and rejecting duplicate keys anywhere ("FILE: $.path.key: duplicate key").
  json parse(const std::string& text) const;

  /// Requires an object whose keys are all in `allowed` (an unknown one is named with a suggestion).
  void expectObject(const json& j, const std::string& path, const std::vector<std::string>& allowed) const;
  /// The member `key` of `obj`, or fails with "missing required key".
  const json& required(const json& obj, const std::string& path, const char* key) const;
  /// a finite number
  double readNumber(const json& j, const std::string& path) const;
  /// true or false
  bool readBool(const json& j, const std::string& path) const;
  /// a string
  std::string readString(const json& j, const std::string& path) const;
  /// an array of 3 finite numbers
  sim::Vec3d readVec3(const json& j, const std::string& path) const;
  /// a number > 0
  double readPositive(const json& j, const std::string& path) const;

  /// Reads the object `j` of table keys into `values`: each key must be in `table`, each value of its
  /// parameter's kind (numbers, booleans, 3-arrays, choice names as strings) and in its range. Relations
  /// between parameters are left to the caller (table.validate once everything is read).
  template <class S>
  void readTable(const json& j, const std::string& path, const sim::ParamTableOf<S>& table, S& values) const {
    if (!j.is_object())
      fail(path, "expected an object, got " + describe(j));
    for (const auto& item : j.items()) {
      const std::string itemPath = memberPath(path, item.key());
      const sim::ParamEntry<S>* info = table.find(item.key());
      if (!info) {
        const std::vector<std::string> known = table.keys();
        fail(itemPath, "unknown " + table.noun() + sim::didYouMean(item.key(), known) +
                           " (known: " + sim::joinNames(known) + ")");
      }
      // the member's type says what JSON value to read; the table's setters check the range
      using Table = sim::ParamTableOf<S>;
      const std::string error = sim::visit(*info, std::as_const(values), [&](const auto& current) {
        using T = std::decay_t<decltype(current)>;
        if constexpr (std::is_same_v<T, std::array<double, 3>>) {
          const sim::Vec3d v = readVec3(item.value(), itemPath);
          return Table::setVec3(values, *info, {v.x(), v.y(), v.z()});
        } else if constexpr (std::is_same_v<T, bool>) {
          return Table::setScalar(values, *info, readBool(item.value(), itemPath) ? 1.0 : 0.0);
        } else if constexpr (std::is_same_v<T, sim::Choice>) {
          return Table::setChoice(values, *info, readString(item.value(), itemPath));
        } else {
          return Table::setScalar(values, *info, readNumber(item.value(), itemPath));
        }
      });
      if (!error.empty())
        fail(itemPath, error);
    }
  }

 private:
  std::string m_fileName;
};

/// Every parameter of `table` in `values` as a JSON object in table order (choices by name), which
/// JsonReader::readTable reads back to the same values.
template <class S>
nlohmann::ordered_json tableToJson(const sim::ParamTableOf<S>& table, const S& values) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const sim::ParamEntry<S>& info : table.entries()) {
    sim::visit(info, values, [&](const auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, sim::Choice>)
        out[info.key] = v.name();
      else
        out[info.key] = v;
    });
  }
  return out;
}

}  // namespace fp::engine
