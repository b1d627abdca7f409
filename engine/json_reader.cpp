#include "engine/json_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

namespace fp::engine {

using nlohmann::json;

std::string formatJsonNumber(double v) {
  std::ostringstream s;
  s << std::setprecision(12) << v;
  return s.str();
}

std::string formatJsonVec3(const sim::Vec3d& v) {
  return "[" + formatJsonNumber(v.x()) + ", " + formatJsonNumber(v.y()) + ", " + formatJsonNumber(v.z()) +
         "]";
}

std::string quoted(const std::string& s) {
  return json(s).dump(-1, ' ', false, json::error_handler_t::replace);
}

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

std::string memberPath(const std::string& parent, const std::string& key) {
  bool identifier = !key.empty() && !std::isdigit(static_cast<unsigned char>(key[0]));
  for (char c : key) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_')
      identifier = false;
  }
  return identifier ? parent + "." + key : parent + "[" + quoted(key) + "]";
}

std::string indexPath(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

std::string readTextFile(const std::string& path, const std::string& what) {
  std::error_code ec;
  std::ifstream in(path, std::ios::binary);
  // A directory opens as a stream on Linux but cannot be read; report it like a missing file.
  if (!in || std::filesystem::is_directory(path, ec))
    throw sim::InputError(path + ": cannot open " + what);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
    throw sim::InputError(path + ": cannot open " + what);
  return text.str();
}

namespace {

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

}  // namespace

void JsonReader::fail(const std::string& path, const std::string& message) const {
  std::string line = m_fileName + ": " + path + ": " + message;
  // Messages from other modules (mesh loader, parameter table) could carry a newline; the contract is one
  // line.
  for (char& c : line) {
    if (c == '\n' || c == '\r' || c == '\t')
      c = ' ';
  }
  throw sim::InputError(line);
}

json JsonReader::parse(const std::string& text) const {
  // One frame per open object or array, to name the path of a duplicate key (nlohmann silently keeps the last
  // one, which would hide a typo'd edit of a file).
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

void JsonReader::expectObject(const json& j, const std::string& path,
                              const std::vector<std::string>& allowed) const {
  if (!j.is_object())
    fail(path, "expected an object, got " + describe(j));
  for (const auto& item : j.items()) {
    if (std::find(allowed.begin(), allowed.end(), item.key()) == allowed.end()) {
      fail(memberPath(path, item.key()), "unknown key" + sim::didYouMean(item.key(), allowed) +
                                             " (allowed: " + sim::joinNames(allowed) + ")");
    }
  }
}

const json& JsonReader::required(const json& obj, const std::string& path, const char* key) const {
  const auto it = obj.find(key);
  if (it == obj.end())
    fail(memberPath(path, key), "missing required key");
  return *it;
}

double JsonReader::readNumber(const json& j, const std::string& path) const {
  if (!j.is_number())
    fail(path, "expected a number, got " + describe(j));
  const double v = j.get<double>();
  if (!std::isfinite(v))
    fail(path, "must be a finite number");
  return v;
}

bool JsonReader::readBool(const json& j, const std::string& path) const {
  if (!j.is_boolean())
    fail(path, "expected a boolean, got " + describe(j));
  return j.get<bool>();
}

std::string JsonReader::readString(const json& j, const std::string& path) const {
  if (!j.is_string())
    fail(path, "expected a string, got " + describe(j));
  return j.get<std::string>();
}

sim::Vec3d JsonReader::readVec3(const json& j, const std::string& path) const {
  if (!j.is_array())
    fail(path, "expected an array of 3 numbers, got " + describe(j));
  if (j.size() != 3)
    fail(path, "expected an array of 3 numbers, got " + std::to_string(j.size()) + " elements");
  sim::Vec3d v;
  for (std::size_t i = 0; i < 3; ++i)
    v[static_cast<Eigen::Index>(i)] = readNumber(j[i], indexPath(path, i));
  return v;
}

double JsonReader::readPositive(const json& j, const std::string& path) const {
  const double v = readNumber(j, path);
  if (!(v > 0.0))
    fail(path, "must be > 0 (got " + formatJsonNumber(v) + ")");
  return v;
}

}  // namespace fp::engine
