#include "sim/param_table.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <iomanip>
#include <sstream>

namespace fp::sim {

std::size_t editDistance(std::string_view a, std::string_view b) {
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

std::string didYouMean(std::string_view name, const std::vector<std::string>& known) {
  std::string best;
  std::size_t bestDistance = 3;  // more edits than this is a different word, not a typo
  for (const std::string& k : known) {
    const std::size_t d = editDistance(name, k);
    if (d < bestDistance) {
      bestDistance = d;
      best = k;
    }
  }
  return best.empty() ? std::string() : " (did you mean " + best + "?)";
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0)
      out += (i + 1 == names.size()) ? " or " : ", ";
    out += names[i];
  }
  return out;
}

std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

namespace param_detail {

namespace {
std::string_view trim(std::string_view t) {
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.front())))
    t.remove_prefix(1);
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back())))
    t.remove_suffix(1);
  return t;
}

/// the whole of `text` as a double, or false
bool toDouble(std::string_view text, double& out) {
  const std::string s(trim(text));
  if (s.empty())
    return false;
  char* end = nullptr;
  errno = 0;
  out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && errno != ERANGE;
}
}  // namespace

std::string checkScalar(const std::string& key, ParamKind kind, double min, double max, double v) {
  if (!std::isfinite(v))
    return key + " must be a finite number";
  if (v < min || v > max) {
    std::ostringstream s;
    s << key << " = " << v << " is out of range [" << min << ", " << max << "]";
    return s.str();
  }
  if (kind != ParamKind::Number && v != std::floor(v))
    return key + " must be an integer";
  return {};
}

std::string parseScalar(const std::string& key, ParamKind kind, std::string_view text, double& out) {
  if (kind == ParamKind::Boolean) {
    std::string t(trim(text));
    std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (t == "true" || t == "on" || t == "yes" || t == "1") {
      out = 1.0;
      return {};
    }
    if (t == "false" || t == "off" || t == "no" || t == "0") {
      out = 0.0;
      return {};
    }
    return key + ": expected true or false, got '" + std::string(text) + "'";
  }
  if (!toDouble(text, out)) {
    return key + ": expected " + (kind == ParamKind::Number ? "a number" : "an integer") + ", got '" +
           std::string(text) + "'";
  }
  return {};
}

std::string parseVec3(const std::string& key, std::string_view text, std::array<double, 3>& out) {
  std::string_view t = trim(text);
  if (t.size() >= 2 && t.front() == '[' && t.back() == ']')
    t = t.substr(1, t.size() - 2);
  std::size_t n = 0;
  bool ok = true;
  while (ok) {
    const std::size_t comma = t.find(',');
    const std::string_view part = t.substr(0, comma);
    ok = n < 3 && toDouble(part, out[n]);
    ++n;
    if (comma == std::string_view::npos)
      break;
    t.remove_prefix(comma + 1);
  }
  if (!ok || n != 3)
    return key + ": expected three numbers x,y,z, got '" + std::string(text) + "'";
  return {};
}

std::string parseChoice(const std::string& key, const std::vector<std::string>& names, std::string_view text,
                        int& out) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == trim(text)) {
      out = int(i);
      return {};
    }
  }
  return key + ": expected " + joinNames(names) + ", got '" + std::string(text) + "'" +
         didYouMean(trim(text), names);
}

std::string formatValue(double v) {
  // the shortest form that reads back to the same double: 0.1 stays "0.1"
  std::string text;
  for (int digits = 6; digits <= 17; ++digits) {
    std::ostringstream t;
    t << std::setprecision(digits) << v;
    text = t.str();
    if (std::strtod(text.c_str(), nullptr) == v)
      break;
  }
  return text;
}

}  // namespace param_detail
}  // namespace fp::sim
