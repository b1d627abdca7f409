#include "input/hand_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fp::input {

namespace {
constexpr const char* kFingerNames[HandModel::kFingers] = {"thumb", "index", "middle", "ring", "little"};
// the thumb's joints bend less than the fingers' at a full curl
constexpr double kThumbCurlShare = 0.6;

double clamp01(double v) {
  return std::clamp(v, 0.0, 1.0);
}
}  // namespace

const char* gestureName(Gesture g) {
  switch (g) {
    case Gesture::Flat:
      return "flat";
    case Gesture::Fist:
      return "fist";
    case Gesture::Point:
      return "point";
  }
  return "?";
}

std::optional<Gesture> parseGesture(std::string_view name) {
  for (Gesture g : {Gesture::Flat, Gesture::Fist, Gesture::Point}) {
    if (name == gestureName(g))
      return g;
  }
  return std::nullopt;
}

GestureChannels gestureChannels(Gesture g) {
  switch (g) {
    case Gesture::Flat:
      return {0.0, 0.0};
    case Gesture::Fist:
      return {1.0, 0.0};
    case Gesture::Point:
      return {1.0, 1.0};
  }
  return {};
}

std::array<double, 5> fingerCurl(double grip, double point) {
  grip = clamp01(grip);
  point = clamp01(point);
  const double others = std::max(grip, point);
  return {others, grip * (1.0 - point), others, others, others};
}

void GestureAnimator::advance(double dt) {
  const GestureChannels goal = gestureChannels(m_target);
  const double step = std::max(0.0, dt) * rate;
  auto approach = [step](double& v, double target) {
    v = v < target ? std::min(target, v + step) : std::max(target, v - step);
  };
  approach(m_current.grip, goal.grip);
  approach(m_current.point, goal.point);
}

const char* fingerName(int f) {
  return f >= 0 && f < HandModel::kFingers ? kFingerNames[f] : "?";
}

HandModel::HandModel(double scale) : m_scale(scale) {
  if (!(scale > 0.2 && scale <= 5.0))
    throw sim::InputError("hand scale must be in (0.2, 5], got " + std::to_string(scale));
  // adult hand, metres: palm 8.4 cm wide (z), 10 cm long (y), 2.6 cm thick (x)
  m_palmHalf = sim::Vec3d(0.013, 0.05, 0.042);
  m_base = {sim::Vec3d(0.006, 0.012, 0.040), sim::Vec3d(0.0, -0.05, 0.028), sim::Vec3d(0.0, -0.05, 0.009),
            sim::Vec3d(0.0, -0.05, -0.010), sim::Vec3d(0.0, -0.047, -0.029)};
  m_radius = {0.0100, 0.0085, 0.0085, 0.0080, 0.0070};
  m_length = {{{0.040, 0.032, 0.026},
               {0.044, 0.026, 0.019},
               {0.048, 0.029, 0.020},
               {0.045, 0.028, 0.020},
               {0.035, 0.020, 0.018}}};
  m_baseRotation.fill(sim::Quatd::Identity());
  // the thumb points down and out to the +z side; its bend axis then swings it across the palm's +x face
  m_baseRotation[0] = sim::Quatd(Eigen::AngleAxisd(-0.6, sim::Vec3d::UnitX()));
}

double HandModel::reachBelowPalm() const {
  return (m_palmHalf.y() + m_length[2][0] + m_length[2][1] + m_length[2][2] + m_radius[2]) * m_scale;
}

std::array<PartPose, HandModel::kParts> HandModel::partPoses(const HandPose& pose) const {
  std::array<PartPose, kParts> parts;
  const sim::Quatd root = pose.orientation.normalized();
  parts[0].position = pose.position;
  parts[0].orientation = root;
  const std::array<double, 5> curl = fingerCurl(pose.grip, pose.point);
  for (int f = 0; f < kFingers; ++f) {
    const double share = f == 0 ? kThumbCurlShare : 1.0;
    sim::Vec3d joint = m_base[f] * m_scale;  // in the hand frame
    double angle = 0.0;
    for (int s = 0; s < kSegments; ++s) {
      angle += curl[f] * share * kCurlRadians[s];
      // finger frame: straight along -y, bending about +z towards +x
      const sim::Quatd bend(Eigen::AngleAxisd(angle, sim::Vec3d::UnitZ()));
      const sim::Quatd local = m_baseRotation[f] * bend;
      const sim::Vec3d dir = local * sim::Vec3d(0.0, -1.0, 0.0);
      const double length = m_length[f][s] * m_scale;
      PartPose& part = parts[1 + f * kSegments + s];
      part.position = pose.position + root * (joint + dir * (0.5 * length));
      part.orientation = (root * local).normalized();
      joint += dir * length;
    }
  }
  return parts;
}

std::vector<sim::ColliderDesc> HandModel::colliders(const HandPose& pose) const {
  const std::array<PartPose, kParts> parts = partPoses(pose);
  std::vector<sim::ColliderDesc> out;
  out.reserve(kParts);
  sim::ColliderDesc palm;
  palm.name = "hand_palm";
  palm.shape = sim::ShapeType::Box;
  palm.halfExtents = m_palmHalf * m_scale;
  palm.position = parts[0].position;
  palm.orientation = parts[0].orientation;
  palm.driven = true;
  out.push_back(palm);
  for (int f = 0; f < kFingers; ++f) {
    for (int s = 0; s < kSegments; ++s) {
      const PartPose& part = parts[1 + f * kSegments + s];
      sim::ColliderDesc c;
      c.name = std::string("hand_") + kFingerNames[f] + "_" + std::to_string(s + 1);
      c.shape = sim::ShapeType::Capsule;
      c.radius = m_radius[f] * m_scale;
      c.halfLength = 0.5 * m_length[f][s] * m_scale;
      c.position = part.position;
      c.orientation = part.orientation;
      c.driven = true;
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace fp::input
