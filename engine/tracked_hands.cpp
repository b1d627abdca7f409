#include "engine/tracked_hands.h"

namespace fp::engine {

std::vector<std::pair<input::HandSide, input::HandJoints>> trackedHandReferences(const sim::SceneDesc& scene,
                                                                                 const TrackedJoints& first,
                                                                                 double handScale) {
  double scale = handScale;
  for (const auto& joints : first) {
    if (joints)
      scale = input::trackedHandScale(*joints);
  }
  const input::HandModel model(scale);
  const input::HandPose rest = restingHandPose(scene, model);
  std::vector<std::pair<input::HandSide, input::HandJoints>> out;
  for (const input::HandSide side : {input::HandSide::Left, input::HandSide::Right}) {
    const auto& tracked = first[std::size_t(side)];
    out.emplace_back(side, tracked ? *tracked : input::jointsOfHandPose(model, rest, side));
  }
  return out;
}

void attachTrackedHands(AppSession& session, const TrackedJoints& first, double handScale) {
  session.setTrackedHands(trackedHandReferences(session.scene(), first, handScale));
  session.requests().reset = true;
  session.applyRequests();
}

void setTrackedTargets(AppSession& session, const TrackedJoints& joints, double frameDt) {
  for (std::size_t k = 0; k < session.trackedHandCount() && k < joints.size(); ++k) {
    std::optional<std::array<input::PartPose, input::HandModel::kParts>> parts;
    if (joints[k])
      parts = input::partPosesFromJoints(*joints[k]);
    session.setTrackedHandTarget(k, parts, frameDt);
  }
}

std::optional<JointReplay> JointReplay::ofScript(const std::string& path) {
  if (path.empty() || !input::JointTrack::isJointFile(path))
    return std::nullopt;
  return JointReplay(input::JointTrack::load(path));
}

TrackedJoints JointReplay::first() const {
  TrackedJoints out;
  if (m_track.frames().empty())
    return out;
  const input::JointFrame& f = m_track.frames().front();
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (f.hands[k].valid)
      out[k] = f.hands[k];
  }
  return out;
}

void JointReplay::attach(AppSession& session, double handScale) const {
  attachTrackedHands(session, first(), handScale);
}

void JointReplay::input(AppSession& session, double frameDt) const {
  const input::JointFrame f = m_track.sample(session.simulation().time());
  TrackedJoints joints;
  for (std::size_t k = 0; k < joints.size(); ++k) {
    if (f.hands[k].valid)
      joints[k] = f.hands[k];
  }
  setTrackedTargets(session, joints, frameDt);
}

JointReplayPlatform::JointReplayPlatform(AppPlatform& inner, const std::optional<JointReplay>& replay,
                                         AppSession& session, double handScale)
    : m_inner(inner), m_replay(replay) {
  if (m_replay)
    m_replay->attach(session, handScale);
}

void JointReplayPlatform::input(AppSession& session, const FrameClock& clock) {
  m_inner.input(session, clock);
  if (m_replay)
    m_replay->input(session, clock.dt);
}

}  // namespace fp::engine
