#include "input/pose_track.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string_view>

#include "input/csv_text.h"

namespace fp::input {

namespace {

using csv::formatExact;
using csv::parseDouble;
using csv::splitCommas;
using csv::trim;

constexpr const char* kHeader = "time,px,py,pz,qw,qx,qy,qz,grip";
constexpr const char* kHeaderPoint = "time,px,py,pz,qw,qx,qy,qz,grip,point";
constexpr int kMaxColumns = 10;

/// World-frame rotation vector (axis * angle) of the shortest rotation taking q0 to q1.
sim::Vec3d rotationVector(const sim::Quatd& q0, const sim::Quatd& q1) {
  sim::Quatd dq = q1 * q0.conjugate();
  // q and -q are the same rotation; w >= 0 picks the representative with angle <= pi (shortest path).
  if (dq.w() < 0.0) {
    dq.coeffs() = -dq.coeffs();
  }
  const double s = dq.vec().norm();
  if (s == 0.0) {
    return sim::Vec3d::Zero();
  }
  // atan2 stays accurate for small angles, where acos(w) loses half the digits.
  const double angle = 2.0 * std::atan2(s, dq.w());
  return dq.vec() * (angle / s);
}

}  // namespace

void PoseTrack::add(const PoseSample& key) {
  if (!std::isfinite(key.time)) {
    throw sim::InputError("pose key: time is not finite");
  }
  if (!key.position.allFinite()) {
    throw sim::InputError("pose key at t=" + formatExact(key.time) + ": position is not finite");
  }
  if (!key.orientation.coeffs().allFinite()) {
    throw sim::InputError("pose key at t=" + formatExact(key.time) + ": orientation is not finite");
  }
  if (!std::isfinite(key.grip) || !std::isfinite(key.point)) {
    throw sim::InputError("pose key at t=" + formatExact(key.time) + ": gesture is not finite");
  }
  if (!m_keys.empty() && !(key.time > m_keys.back().time)) {
    throw sim::InputError("pose key at t=" + formatExact(key.time) +
                          ": time is not after the previous key (t=" + formatExact(m_keys.back().time) + ")");
  }
  const double norm = key.orientation.norm();
  if (norm < 1e-9) {
    throw sim::InputError("pose key at t=" + formatExact(key.time) + ": orientation quaternion is zero");
  }

  PoseSample stored;
  stored.time = key.time;
  stored.position = key.position;
  stored.grip = key.grip;
  stored.point = key.point;
  stored.orientation = key.orientation;
  // Renormalise only when visibly off: dividing an already unit quaternion by its norm can move the last bit,
  // which would break the exact save/load round trip.
  if (std::abs(norm - 1.0) > 1e-12) {
    stored.orientation.coeffs() /= norm;
  }
  // Keys carry poses only; velocities are derived per segment by sample().
  m_keys.push_back(stored);
}

double PoseTrack::duration() const {
  return m_keys.empty() ? 0.0 : m_keys.back().time;
}

PoseSample PoseTrack::sample(double t) const {
  PoseSample out;
  out.time = t;
  if (m_keys.empty()) {
    return out;
  }
  const PoseSample& first = m_keys.front();
  const PoseSample& last = m_keys.back();
  // Before the track, with a single key, or for NaN (which fails every comparison): the first pose, at rest.
  if (m_keys.size() < 2 || !(t >= first.time)) {
    out.position = first.position;
    out.orientation = first.orientation;
    out.grip = first.grip;
    out.point = first.point;
    return out;
  }
  if (t > last.time) {  // after the track: the last pose, at rest
    out.position = last.position;
    out.orientation = last.orientation;
    out.grip = last.grip;
    out.point = last.point;
    return out;
  }

  // Segment [i, i+1] with key(i).time <= t < key(i+1).time; t == last time belongs to the final segment.
  const auto upper = std::upper_bound(m_keys.begin(), m_keys.end(), t,
                                      [](double value, const PoseSample& key) { return value < key.time; });
  const size_t i1 = std::min(static_cast<size_t>(upper - m_keys.begin()), m_keys.size() - 1);
  const size_t i0 = i1 - 1;
  const PoseSample& k0 = m_keys[i0];
  const PoseSample& k1 = m_keys[i1];
  const double dt = k1.time - k0.time;
  const double a = (t - k0.time) / dt;

  // (1-a)*x0 + a*x1 rather than x0 + a*(x1-x0): both ends are then reproduced exactly.
  out.position = (1.0 - a) * k0.position + a * k1.position;
  out.grip = (1.0 - a) * k0.grip + a * k1.grip;
  out.point = (1.0 - a) * k0.point + a * k1.point;
  if (t == k1.time) {
    out.orientation = k1.orientation;  // exact key, and not its negated twin that slerp may return
  } else {
    out.orientation = k0.orientation.slerp(a, k1.orientation);  // Eigen's slerp follows the shortest arc
  }
  out.linearVelocity = (k1.position - k0.position) / dt;
  out.angularVelocity = rotationVector(k0.orientation, k1.orientation) / dt;
  return out;
}

PoseTrack PoseTrack::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw sim::InputError(path + ": cannot open pose track for reading");
  }
  PoseTrack track;
  std::string raw;
  int lineNumber = 0;
  bool headerSeen = false;
  int columns = 9;
  while (std::getline(in, raw)) {
    ++lineNumber;
    const std::string_view line = trim(raw);
    const std::string where = path + ":" + std::to_string(lineNumber) + ": ";
    if (!headerSeen) {
      if (line == kHeaderPoint) {
        columns = kMaxColumns;
      } else if (line != kHeader) {
        throw sim::InputError(where + "expected header \"" + kHeader + "\" or \"" + kHeaderPoint + "\"");
      }
      headerSeen = true;
      continue;
    }
    if (line.empty()) {
      continue;  // tolerate blank lines, e.g. a trailing one added by an editor
    }
    const std::vector<std::string_view> fields = splitCommas(line);
    if (static_cast<int>(fields.size()) != columns) {
      throw sim::InputError(where + "expected " + std::to_string(columns) + " columns, found " +
                            std::to_string(fields.size()));
    }
    double v[kMaxColumns] = {};
    for (int c = 0; c < columns; ++c) {
      if (!parseDouble(fields[c], v[c])) {
        throw sim::InputError(where + "column " + std::to_string(c + 1) + ": bad number \"" +
                              std::string(fields[c]) + "\"");
      }
    }
    PoseSample key;
    key.time = v[0];
    key.position = sim::Vec3d(v[1], v[2], v[3]);
    key.orientation = sim::Quatd(v[4], v[5], v[6], v[7]);  // Eigen's constructor order is w, x, y, z
    key.grip = v[8];
    key.point = v[9];
    try {
      track.add(key);
    } catch (const sim::InputError& e) {
      throw sim::InputError(where + e.what());
    }
  }
  if (!headerSeen) {
    throw sim::InputError(path + ":1: empty file, expected header \"" + kHeader + "\"");
  }
  return track;
}

void PoseTrack::save(const std::string& path) const {
  std::ofstream out(path, std::ios::trunc);
  if (!out) {
    throw sim::InputError(path + ": cannot open pose track for writing");
  }
  const bool point =
      std::any_of(m_keys.begin(), m_keys.end(), [](const PoseSample& k) { return k.point != 0.0; });
  const int columns = point ? kMaxColumns : kMaxColumns - 1;
  out << (point ? kHeaderPoint : kHeader) << '\n';
  for (const PoseSample& k : m_keys) {
    const double values[kMaxColumns] = {k.time,
                                        k.position.x(),
                                        k.position.y(),
                                        k.position.z(),
                                        k.orientation.w(),
                                        k.orientation.x(),
                                        k.orientation.y(),
                                        k.orientation.z(),
                                        k.grip,
                                        k.point};
    for (int c = 0; c < columns; ++c) {
      out << (c == 0 ? "" : ",") << formatExact(values[c]);
    }
    out << '\n';
  }
  out.close();
  if (out.fail()) {
    throw sim::InputError(path + ": write failed");
  }
}

}  // namespace fp::input
