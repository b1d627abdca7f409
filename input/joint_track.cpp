#include "input/joint_track.h"

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

constexpr const char* kHeader = "time,hand,joint,valid,px,py,pz,qw,qx,qy,qz,radius";
constexpr int kColumns = 12;

}  // namespace

void JointTrack::add(const JointFrame& frame) {
  const std::string at = "joint frame at t=" + formatExact(frame.time) + ": ";
  if (!std::isfinite(frame.time))
    throw sim::InputError("joint frame: time is not finite");
  if (!m_frames.empty() && !(frame.time > m_frames.back().time))
    throw sim::InputError(
        at + "time is not after the previous frame (t=" + formatExact(m_frames.back().time) + ")");
  JointFrame stored = frame;
  for (int h = 0; h < 2; ++h) {
    HandJoints& hand = stored.hands[h];
    if (!hand.valid)
      continue;
    for (int j = 0; j < kHandJoints; ++j) {
      JointPose& p = hand.joint[j];
      const std::string what = at + handSideName(HandSide(h)) + " " + jointName(j) + ": ";
      if (!p.position.allFinite() || !p.orientation.coeffs().allFinite() || !std::isfinite(p.radius))
        throw sim::InputError(what + "value is not finite");
      if (!(p.radius > 0.0))
        throw sim::InputError(what + "radius must be > 0");
      const double norm = p.orientation.norm();
      if (norm < 1e-9)
        throw sim::InputError(what + "orientation quaternion is zero");
      if (std::abs(norm - 1.0) > 1e-12)  // keeps exact round trips of unit quaternions
        p.orientation.coeffs() /= norm;
    }
  }
  m_frames.push_back(stored);
}

double JointTrack::duration() const {
  return m_frames.empty() ? 0.0 : m_frames.back().time;
}

JointFrame JointTrack::sample(double t) const {
  if (m_frames.empty()) {
    JointFrame none;
    none.time = t;
    return none;
  }
  if (m_frames.size() < 2 || !(t > m_frames.front().time)) {
    JointFrame out = m_frames.front();
    out.time = t;
    return out;
  }
  if (t >= m_frames.back().time) {
    JointFrame out = m_frames.back();
    out.time = t;
    return out;
  }
  const auto upper = std::upper_bound(m_frames.begin(), m_frames.end(), t,
                                      [](double value, const JointFrame& f) { return value < f.time; });
  const JointFrame& f1 = *upper;
  const JointFrame& f0 = *(upper - 1);
  if (t == f0.time)
    return f0;  // a recorded instant as recorded, bit for bit (a replay of the run that recorded it)
  const double a = (t - f0.time) / (f1.time - f0.time);
  JointFrame out = f0;
  out.time = t;
  for (int h = 0; h < 2; ++h) {
    if (!f0.hands[h].valid || !f1.hands[h].valid)
      continue;
    for (int j = 0; j < kHandJoints; ++j) {
      const JointPose& p0 = f0.hands[h].joint[j];
      const JointPose& p1 = f1.hands[h].joint[j];
      JointPose& p = out.hands[h].joint[j];
      p.position = (1.0 - a) * p0.position + a * p1.position;
      p.orientation = p0.orientation.slerp(a, p1.orientation).normalized();
      p.radius = (1.0 - a) * p0.radius + a * p1.radius;
    }
  }
  return out;
}

void JointTrack::put(const JointFrame& frame) {
  if (!m_frames.empty() && frame.time == m_frames.back().time) {
    const JointFrame previous = m_frames.back();
    m_frames.pop_back();
    try {
      add(frame);
    } catch (...) {
      m_frames.push_back(previous);
      throw;
    }
    return;
  }
  add(frame);
}

const char* JointTrack::header() {
  return kHeader;
}

bool JointTrack::isJointFile(const std::string& path) {
  return csv::firstLine(path) == kHeader;
}

JointTrack JointTrack::load(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw sim::InputError(path + ": cannot open joint recording for reading");
  JointTrack track;
  std::string raw;
  int lineNumber = 0;
  bool headerSeen = false;
  bool open = false;  // a frame is being read
  JointFrame frame;
  std::array<int, 2> next = {0, 0};  // the joint each hand's next line must be
  std::array<int, 2> validity = {-1, -1};
  std::string frameStart;
  auto finish = [&]() {
    for (int h = 0; h < 2; ++h) {
      if (next[h] != 0 && next[h] != kHandJoints)
        throw sim::InputError(frameStart + handSideName(HandSide(h)) + " hand has " +
                              std::to_string(next[h]) + " of 26 joints");
      frame.hands[h].valid = next[h] == kHandJoints && validity[h] == 1;
    }
    try {
      track.add(frame);
    } catch (const sim::InputError& e) {
      throw sim::InputError(frameStart + e.what());
    }
  };
  while (std::getline(in, raw)) {
    ++lineNumber;
    const std::string_view line = trim(raw);
    const std::string where = path + ":" + std::to_string(lineNumber) + ": ";
    if (!headerSeen) {
      if (line != kHeader)
        throw sim::InputError(where + "expected header \"" + kHeader + "\"");
      headerSeen = true;
      continue;
    }
    if (line.empty())
      continue;
    const std::vector<std::string_view> f = splitCommas(line);
    if (int(f.size()) != kColumns)
      throw sim::InputError(where + "expected " + std::to_string(kColumns) + " columns, found " +
                            std::to_string(f.size()));
    double time = 0.0;
    if (!parseDouble(f[0], time))
      throw sim::InputError(where + "column 1: bad number \"" + std::string(f[0]) + "\"");
    int h = -1;
    if (f[1] == "left")
      h = 0;
    else if (f[1] == "right")
      h = 1;
    else
      throw sim::InputError(where + "column 2: hand must be left or right, got \"" + std::string(f[1]) +
                            "\"");
    const std::optional<int> joint = parseJointName(f[2]);
    if (!joint)
      throw sim::InputError(where + "column 3: unknown joint \"" + std::string(f[2]) + "\"");
    if (f[3] != "0" && f[3] != "1")
      throw sim::InputError(where + "column 4: valid must be 0 or 1");
    double v[kColumns] = {};
    for (int c = 4; c < kColumns; ++c) {
      if (!parseDouble(f[c], v[c]))
        throw sim::InputError(where + "column " + std::to_string(c + 1) + ": bad number \"" +
                              std::string(f[c]) + "\"");
    }
    if (!open || time != frame.time) {
      if (open)
        finish();
      frame = JointFrame{};
      frame.time = time;
      next = {0, 0};
      validity = {-1, -1};
      frameStart = where;
      open = true;
    }
    if (*joint != next[h])
      throw sim::InputError(where + "expected " + handSideName(HandSide(h)) + " joint " +
                            (next[h] < kHandJoints ? jointName(next[h]) : "(none: the hand has 26)") +
                            ", got " + std::string(f[2]));
    const int valid = f[3] == "1" ? 1 : 0;
    if (validity[h] != -1 && validity[h] != valid)
      throw sim::InputError(where + "valid differs between the joints of one hand");
    validity[h] = valid;
    JointPose& p = frame.hands[h].joint[*joint];
    p.position = sim::Vec3d(v[4], v[5], v[6]);
    p.orientation = sim::Quatd(v[7], v[8], v[9], v[10]);
    p.radius = v[11];
    ++next[h];
  }
  if (!headerSeen)
    throw sim::InputError(path + ":1: empty file, expected header \"" + kHeader + "\"");
  if (open)
    finish();
  return track;
}

void JointTrack::save(const std::string& path) const {
  std::ofstream out(path, std::ios::trunc);
  if (!out)
    throw sim::InputError(path + ": cannot open joint recording for writing");
  out << kHeader << '\n';
  for (const JointFrame& f : m_frames) {
    for (int h = 0; h < 2; ++h) {
      const HandJoints& hand = f.hands[h];
      for (int j = 0; j < kHandJoints; ++j) {
        const JointPose& p = hand.joint[j];
        out << formatExact(f.time) << ',' << handSideName(HandSide(h)) << ',' << jointName(j) << ','
            << (hand.valid ? 1 : 0);
        const double values[8] = {p.position.x(),    p.position.y(),    p.position.z(),    p.orientation.w(),
                                  p.orientation.x(), p.orientation.y(), p.orientation.z(), p.radius};
        for (double v : values)
          out << ',' << formatExact(v);
        out << '\n';
      }
    }
  }
  out.close();
  if (out.fail())
    throw sim::InputError(path + ": write failed");
}

}  // namespace fp::input
