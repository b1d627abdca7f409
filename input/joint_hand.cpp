#include "input/joint_hand.h"

#include "input/hand_driver.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace fp::input {

namespace {

constexpr const char* kJointNames[kHandJoints] = {"palm",
                                                  "wrist",
                                                  "thumb_metacarpal",
                                                  "thumb_proximal",
                                                  "thumb_distal",
                                                  "thumb_tip",
                                                  "index_metacarpal",
                                                  "index_proximal",
                                                  "index_intermediate",
                                                  "index_distal",
                                                  "index_tip",
                                                  "middle_metacarpal",
                                                  "middle_proximal",
                                                  "middle_intermediate",
                                                  "middle_distal",
                                                  "middle_tip",
                                                  "ring_metacarpal",
                                                  "ring_proximal",
                                                  "ring_intermediate",
                                                  "ring_distal",
                                                  "ring_tip",
                                                  "little_metacarpal",
                                                  "little_proximal",
                                                  "little_intermediate",
                                                  "little_distal",
                                                  "little_tip"};

/// The two joints of segment s of finger f (HandModel's order): the thumb's bones start at its metacarpal,
/// the fingers' at their proximal joint (their metacarpals lie inside the palm).
std::pair<int, int> segmentJoints(int f, int s) {
  const int first = f == 0 ? 2 : 6 + 5 * (f - 1) + 1;
  return {first + s, first + s + 1};
}

/// Part coordinates -> joint coordinates (part frame = joint frame * this): a part's local y runs along the
/// bone towards the wrist (the joint's +z), its local x out of the palm side (the joint's -y), z = x cross y
/// (the joint's -x).
const sim::Quatd& jointFromPart() {
  static const sim::Quatd q = [] {
    Eigen::Matrix3d m;
    m.col(0) = sim::Vec3d(0.0, -1.0, 0.0);
    m.col(1) = sim::Vec3d(0.0, 0.0, 1.0);
    m.col(2) = sim::Vec3d(-1.0, 0.0, 0.0);
    return sim::Quatd(m);
  }();
  return q;
}

/// mirror across the hand frame's z = 0 plane: (x, y, z) -> (x, y, -z); a rotation R -> S R S
sim::Quatd mirrored(const sim::Quatd& q) {
  return sim::Quatd(q.w(), -q.x(), -q.y(), q.z());
}

/// the shortest rotation taking direction a to direction b (Eigen's FromTwoVectors without its SVD branch)
sim::Quatd shortestArc(const sim::Vec3d& a, const sim::Vec3d& b) {
  const sim::Vec3d u = a.normalized(), v = b.normalized();
  const double d = u.dot(v);
  if (d < -1.0 + 1e-12) {
    const sim::Vec3d side = std::abs(u.x()) < 0.9 ? sim::Vec3d::UnitX() : sim::Vec3d::UnitY();
    return sim::Quatd(Eigen::AngleAxisd(sim::kPi, u.cross(side).normalized()));
  }
  const sim::Vec3d c = u.cross(v);
  return sim::Quatd(1.0 + d, c.x(), c.y(), c.z()).normalized();
}

double palmToTipLength(const HandJoints& j) {
  const auto d = [&](int a, int b) { return (j.joint[a].position - j.joint[b].position).norm(); };
  // wrist to the middle finger's knuckle, then along its phalanges: independent of the curl
  return d(1, 12) + d(12, 13) + d(13, 14) + d(14, 15);
}

}  // namespace

const char* jointName(int j) {
  return j >= 0 && j < kHandJoints ? kJointNames[j] : "?";
}

std::optional<int> parseJointName(std::string_view name) {
  for (int j = 0; j < kHandJoints; ++j) {
    if (name == kJointNames[j])
      return j;
  }
  return std::nullopt;
}

const char* handSideName(HandSide side) {
  return side == HandSide::Left ? "left" : "right";
}

std::array<PartPose, HandModel::kParts> partPosesFromJoints(const HandJoints& joints) {
  std::array<PartPose, HandModel::kParts> parts;
  const JointPose& palm = joints.joint[int(HandJoint::Palm)];
  parts[0].position = palm.position;
  parts[0].orientation = (palm.orientation * jointFromPart()).normalized();
  for (int f = 0; f < HandModel::kFingers; ++f) {
    for (int s = 0; s < HandModel::kSegments; ++s) {
      const auto [a, b] = segmentJoints(f, s);
      const JointPose& ja = joints.joint[a];
      const JointPose& jb = joints.joint[b];
      PartPose& part = parts[1 + f * HandModel::kSegments + s];
      part.position = 0.5 * (ja.position + jb.position);
      // the joint's own frame, turned the least so its bone axis runs exactly from joint to joint
      const sim::Quatd q0 = (ja.orientation * jointFromPart()).normalized();
      const sim::Vec3d axis = ja.position - jb.position;
      part.orientation =
          axis.norm() > 1e-9 ? (shortestArc(q0 * sim::Vec3d::UnitY(), axis) * q0).normalized() : q0;
    }
  }
  return parts;
}

std::vector<sim::ColliderDesc> jointHandColliders(const HandJoints& reference, HandSide side) {
  const std::array<PartPose, HandModel::kParts> parts = partPosesFromJoints(reference);
  const auto& j = reference.joint;
  const std::string prefix = std::string(handSideName(side)) + "_";
  std::vector<sim::ColliderDesc> out;
  out.reserve(HandModel::kParts);
  sim::ColliderDesc palm;
  palm.name = prefix + "palm";
  palm.shape = sim::ShapeType::Box;
  const double knuckles = (j[7].position - j[22].position).norm();
  palm.halfExtents = sim::Vec3d(j[0].radius, (j[0].position - j[1].position).norm(),
                                0.5 * knuckles + 0.5 * (j[7].radius + j[22].radius));
  palm.position = parts[0].position;
  palm.orientation = parts[0].orientation;
  palm.driven = true;
  out.push_back(palm);
  for (int f = 0; f < HandModel::kFingers; ++f) {
    for (int s = 0; s < HandModel::kSegments; ++s) {
      const auto [a, b] = segmentJoints(f, s);
      const PartPose& part = parts[1 + f * HandModel::kSegments + s];
      sim::ColliderDesc c;
      c.name = prefix + fingerName(f) + "_" + std::to_string(s + 1);
      c.shape = sim::ShapeType::Capsule;
      c.radius = 0.5 * (j[a].radius + j[b].radius);
      c.halfLength = 0.5 * (j[a].position - j[b].position).norm();
      c.position = part.position;
      c.orientation = part.orientation;
      c.driven = true;
      out.push_back(c);
    }
  }
  return out;
}

HandJoints jointsOfHandPose(const HandModel& model, const HandPose& pose, HandSide side) {
  // the right hand in the hand frame, then mirrored for the left, then placed
  HandPose local = pose;
  local.position = sim::Vec3d::Zero();
  local.orientation = sim::Quatd::Identity();
  const std::array<PartPose, HandModel::kParts> parts = model.partPoses(local);
  const sim::Vec3d half = model.palmHalfExtents();
  HandJoints out;
  out.valid = true;
  auto set = [&](int index, const sim::Vec3d& p, const sim::Quatd& partOrientation, double radius) {
    JointPose& jp = out.joint[index];
    jp.position = p;
    jp.orientation = (partOrientation * jointFromPart().conjugate()).normalized();
    jp.radius = radius;
  };
  set(0, sim::Vec3d::Zero(), sim::Quatd::Identity(), half.x());
  const sim::Vec3d wrist(0.0, half.y(), 0.0);
  set(1, wrist, sim::Quatd::Identity(), half.x());
  for (int f = 0; f < HandModel::kFingers; ++f) {
    const double r = model.fingerRadius(f);
    const int first = segmentJoints(f, 0).first;
    for (int s = 0; s < HandModel::kSegments; ++s) {
      const PartPose& part = parts[1 + f * HandModel::kSegments + s];
      const sim::Vec3d dir = part.orientation * sim::Vec3d(0.0, -1.0, 0.0);
      const double length = model.segmentLength(f, s);
      set(first + s, part.position - 0.5 * length * dir, part.orientation, r);
      if (s == HandModel::kSegments - 1)
        set(first + s + 1, part.position + 0.5 * length * dir, part.orientation, r);
    }
    if (f > 0) {
      // the metacarpal joint lies in the palm, a third of the way from the wrist to the knuckle
      const sim::Vec3d knuckle = out.joint[first].position;
      set(first - 1, wrist + (knuckle - wrist) / 3.0, sim::Quatd::Identity(), r);
    }
  }
  const sim::Quatd root = pose.orientation.normalized();
  for (JointPose& jp : out.joint) {
    if (side == HandSide::Left) {
      jp.position.z() = -jp.position.z();
      // mirror the part frame (S R S), not the joint frame, so the joint frame stays a rotation
      jp.orientation =
          (mirrored(jp.orientation * jointFromPart()) * jointFromPart().conjugate()).normalized();
    }
    jp.position = pose.position + root * jp.position;
    jp.orientation = (root * jp.orientation).normalized();
  }
  return out;
}

HandPose controllerHandPose(const sim::Vec3d& gripPosition, const sim::Quatd& gripOrientation, double trigger,
                            double squeeze, HandSide side) {
  // hand frame -> grip frame: the palm (+x) faces the grip's -x (right) or +x (left), the wrist (+y) is at
  // +z, the thumb side (+z of the right model, -z of the mirrored left one) is up (+y)
  Eigen::Matrix3d m;
  if (side == HandSide::Right) {
    m.col(0) = sim::Vec3d(-1.0, 0.0, 0.0);
    m.col(1) = sim::Vec3d(0.0, 0.0, 1.0);
    m.col(2) = sim::Vec3d(0.0, 1.0, 0.0);
  } else {
    m.col(0) = sim::Vec3d(1.0, 0.0, 0.0);
    m.col(1) = sim::Vec3d(0.0, 0.0, 1.0);
    m.col(2) = sim::Vec3d(0.0, -1.0, 0.0);
  }
  const double t = std::clamp(trigger, 0.0, 1.0);
  const double s = std::clamp(squeeze, 0.0, 1.0);
  HandPose pose;
  pose.position = gripPosition;
  pose.orientation = (gripOrientation.normalized() * sim::Quatd(m)).normalized();
  pose.grip = std::max(s, t);
  pose.point = std::max(0.0, s - t);
  return pose;
}

double trackedHandScale(const HandJoints& joints) {
  static const double model = palmToTipLength(jointsOfHandPose(HandModel(1.0), HandPose{}, HandSide::Right));
  return palmToTipLength(joints) / model;
}

void PartMotion::set(const Parts& from, const Parts& to, double t0, double t1) {
  m_keys.assign({from, to});
  m_t0 = t0;
  m_t1 = t1 > t0 ? t1 : t0 + 1e-9;
}

void PartMotion::set(const Parts& from, const std::vector<Parts>& through, double t0, double t1) {
  m_keys.assign(1, from);
  m_keys.insert(m_keys.end(), through.begin(), through.end());
  if (m_keys.size() < 2)
    m_keys.push_back(from);
  m_t0 = t0;
  m_t1 = t1 > t0 ? t1 : t0 + 1e-9;
}

PartMotion::Parts PartMotion::sample(double t) const {
  const double u = std::clamp((t - m_t0) / (m_t1 - m_t0), 0.0, 1.0);
  // the segment, and the fraction along it (one segment: u itself, as a two-key motion always was)
  const std::size_t segments = m_keys.size() - 1;
  const double s = u * double(segments);
  const std::size_t i = std::min(std::size_t(s), segments - 1);
  const double f = s - double(i);
  const Parts& from = m_keys[i];
  const Parts& to = m_keys[i + 1];
  Parts out;
  for (int k = 0; k < HandModel::kParts; ++k) {
    out[k].position = (1.0 - f) * from[k].position + f * to[k].position;
    out[k].orientation = from[k].orientation.slerp(f, to[k].orientation).normalized();
  }
  return out;
}

void PartMotion::apply(sim::Simulation& simulation, std::size_t first, double h) const {
  const double step = h > 0.0 ? h : 1e-3;
  const double t = simulation.time();
  const auto now = sample(t);
  const auto next = sample(t + step);
  for (int k = 0; k < HandModel::kParts; ++k) {
    const sim::Vec3d v = (next[k].position - now[k].position) / step;
    const sim::Vec3d w = rotationBetween(now[k].orientation, next[k].orientation) / step;
    simulation.setColliderPose(first + std::size_t(k), now[k].position, now[k].orientation, v, w);
  }
}

const std::array<PartPose, HandModel::kParts>& HandPresence::update(
    const std::optional<std::array<PartPose, HandModel::kParts>>& tracked, double dt) {
  if (!m_placed) {
    if (tracked) {
      m_parts = *tracked;
      m_placed = true;
      m_following = true;
    }
    return m_parts;
  }
  std::array<PartPose, HandModel::kParts> target;
  if (tracked) {
    target = *tracked;
  } else {
    // lost: the hand as it was, lifted until its lowest part is at the parking height
    double lowest = m_parts[0].position.y();
    for (const PartPose& p : m_parts)
      lowest = std::min(lowest, p.position.y());
    target = m_parts;
    const double lift = std::max(0.0, m_parkHeight - lowest);
    for (PartPose& p : target)
      p.position.y() += lift;
  }
  if (tracked && m_following) {
    m_parts = target;  // a tracked hand moves as the joints do
    return m_parts;
  }
  double farthest = 0.0;
  for (int k = 0; k < HandModel::kParts; ++k)
    farthest = std::max(farthest, (target[k].position - m_parts[k].position).norm());
  const double reach = m_speed * std::max(0.0, dt);
  if (farthest <= reach) {
    m_parts = target;
    m_following = tracked.has_value();
    return m_parts;
  }
  const double u = reach / farthest;
  for (int k = 0; k < HandModel::kParts; ++k) {
    m_parts[k].position += u * (target[k].position - m_parts[k].position);
    m_parts[k].orientation = m_parts[k].orientation.slerp(u, target[k].orientation).normalized();
  }
  m_following = false;
  return m_parts;
}

}  // namespace fp::input
