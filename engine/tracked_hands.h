#pragma once
/// The session's two tracked hands (headset, joint recordings): sized from the first frame a hand is tracked
/// in, driven part by part from tracked joints, and a joint recording (input/joint_track) replayed by them in
/// the desktop window and headless (`--hand-script` with a joint file) frame for frame as the headset run
/// that recorded it.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/app_loop.h"
#include "input/joint_hand.h"
#include "input/joint_track.h"

namespace fp::engine {

/// Both hands' joints in one frame, by input::HandSide; empty: not tracked.
using TrackedJoints = std::array<std::optional<input::HandJoints>, 2>;

/// The references the two tracked hands (left, right) are sized from: a hand tracked in `first` by its own
/// joints, the other one by the model hand at the tracked one's size (input::trackedHandScale), both by the
/// model at `handScale` when neither is tracked; the model's joints rest over the water of `scene`.
std::vector<std::pair<input::HandSide, input::HandJoints>> trackedHandReferences(const sim::SceneDesc& scene,
                                                                                 const TrackedJoints& first,
                                                                                 double handScale);

/// Attaches the two tracked hands to `session`, sized by trackedHandReferences, and rebuilds it (the
/// simulation starts over, at time 0). The simulation must be idle.
void attachTrackedHands(AppSession& session, const TrackedJoints& first, double handScale);

/// The tracked hands' targets for the coming frame of `frameDt` [s] (> 0) from `joints` in the scene's frame.
void setTrackedTargets(AppSession& session, const TrackedJoints& joints, double frameDt);

/// A joint recording replayed by the session's tracked hands. A frame whose simulated time is a recorded
/// frame's time gets that frame's joints exactly, so a replay of a headset run that recorded at its frames'
/// simulated times (--record-hands) reproduces it bit for bit in fixed steps.
class JointReplay {
 public:
  /// `track`: the recording, times in simulated seconds from the start
  explicit JointReplay(input::JointTrack track) : m_track(std::move(track)) {}
  /// the recording of a hand script told by its header (input::JointTrack::header()), or nothing for a
  /// pose track; throws sim::InputError naming the file and line for a malformed joint recording
  static std::optional<JointReplay> ofScript(const std::string& path);
  /// the recording's first frame's tracked hands
  TrackedJoints first() const;
  /// attaches the tracked hands sized from the recording's first frame (attachTrackedHands)
  void attach(AppSession& session, double handScale) const;
  /// sets the tracked hands' targets for the coming frame from the recording at the simulated time now
  void input(AppSession& session, double frameDt) const;

 private:
  input::JointTrack m_track;
};

/// A platform with a joint recording replayed in it: every edge is `inner`'s, and after its input the
/// replay sets the tracked hands (no replay: `inner` as it is).
class JointReplayPlatform : public AppPlatform {
 public:
  /// attaches the replay's hands to `session` (see JointReplay::attach)
  JointReplayPlatform(AppPlatform& inner, const std::optional<JointReplay>& replay, AppSession& session,
                      double handScale);
  bool running() override { return m_inner.running(); }
  FrameClock beginFrame() override { return m_inner.beginFrame(); }
  void input(AppSession& session, const FrameClock& clock) override;
  void capture(AppSession& session, int frame) override { m_inner.capture(session, frame); }
  void draw(AppSession& session, int frame) override { m_inner.draw(session, frame); }
  double stepBudget() const override { return m_inner.stepBudget(); }
  void restart(AppSession& session) override { m_inner.restart(session); }

 private:
  AppPlatform& m_inner;
  const std::optional<JointReplay>& m_replay;
};

}  // namespace fp::engine
