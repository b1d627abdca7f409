#pragma once
/// The one frame loop of every mode. The desktop window, the headless runs (a scene alone, or a recorded hand
/// replayed) and the OpenXR headset are platforms: they differ only in the edges the loop calls (the frame's
/// timing, input, taking the frame, drawing). Every frame:
///
///   the platform's timing -> finish the previous frame's steps -> input (events, panel, hand) -> apply
///   requests and live parameters -> capture the idle state -> start this frame's steps on the TBB workers
///   -> draw and present
///
/// so the simulation runs while the frame is drawn from the last completed state. A platform with a deadline
/// (the headset) may ask not to wait for the steps: while they still run, the frame takes no state and
/// starts no steps, it draws the last captured state again (inputWhileStepping, draw), and the next frame
/// that finds them done joins them and starts the next ones over the time of the frames in between.

#include <limits>
#include <optional>

#include "engine/app_session.h"

namespace fp::engine {

/// What the platform gives one frame: the time it covers, and whether to step the simulation and draw.
struct FrameClock {
  /// time the frame covers [s]: the wall time since the last frame (desktop), one frame of the scene
  /// (headless), the predicted display period (headset); the session scales it (or, in fixed steps, advances
  /// one frame of the scene)
  double dt = 0.0;
  bool simulate = true;  ///< start solver steps this frame
  bool render = true;    ///< capture and draw this frame (false: a frame the display does not show)
  bool restart = false;  ///< the platform lost its session: the loop joins the steps and calls restart()
  /// false: when the last steps still run, do not wait for them: the frame draws the last captured state
  /// again (a display with a deadline: the headset). A fixed-step session always waits (its frames are
  /// deterministic).
  bool waitForSteps = true;
};

/// The edges of the loop.
class AppPlatform {
 public:
  virtual ~AppPlatform() = default;
  /// false once the user closed the window, asked to quit, or the run reached its end
  virtual bool running() = 0;
  /// the coming frame's timing (desktop: the wall clock; headless: a fixed step; headset: the predicted
  /// display time); called first in every frame, while the last frame's steps may still run
  virtual FrameClock beginFrame() = 0;
  /// events and controls of the frame: hand target, requests, parameter edits; the simulation is idle
  virtual void input(AppSession& session, const FrameClock& clock) = 0;
  /// input of a frame drawn while the last steps still run (FrameClock::waitForSteps): the simulation is
  /// not idle, so only what the session queues for the next steps (AppSession::setTrackedHandTarget)
  virtual void inputWhileStepping(AppSession&, const FrameClock&) {}
  /// takes what the frame shows from the idle simulation (particle upload, spray, statistics, export)
  virtual void capture(AppSession& session, int frame) = 0;
  /// draws and presents the frame while the simulation steps
  virtual void draw(AppSession& session, int frame) = 0;
  /// wall time the coming frame's steps may take [s] (infinite: all of the frame's simulated time)
  virtual double stepBudget() const { return std::numeric_limits<double>::infinity(); }
  /// starts the platform's session again after beginFrame asked for it (a lost headset session); the
  /// simulation is idle
  virtual void restart(AppSession&) {}
};

/// Runs the loop until the platform stops or `frames` frames were counted; returns the frames counted (a
/// frame that restarts the platform does not count).
int runAppLoop(AppSession& session, AppPlatform& platform, std::optional<int> frames);

}  // namespace fp::engine
