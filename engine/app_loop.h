#pragma once
/// The one frame loop of the interactive modes. The desktop window, the headless hand replay and (later) the
/// OpenXR headset are platforms: they differ only in the edges the loop calls (input, taking the frame,
/// drawing). Every frame:
///
///   finish the previous frame's steps -> input (events, panel, hand) -> apply requests and live parameters
///   -> capture the idle state for drawing -> start this frame's steps on the TBB workers -> draw and present
///
/// so the simulation runs while the frame is drawn from the last completed state.

#include <limits>
#include <optional>

#include "engine/app_session.h"

namespace fp::engine {

/// The edges of the loop.
class AppPlatform {
 public:
  virtual ~AppPlatform() = default;
  /// false once the user closed the window or asked to quit
  virtual bool running() = 0;
  /// events and controls of the frame: hand target, requests, parameter edits; the simulation is idle
  virtual void input(AppSession& session, double wallDt) = 0;
  /// takes what the frame shows from the idle simulation (particle upload, spray, statistics)
  virtual void capture(AppSession& session, int frame) = 0;
  /// draws and presents the frame while the simulation steps
  virtual void draw(AppSession& session, int frame) = 0;
  /// wall time the coming frame's steps may take [s] (infinite: all of the frame's simulated time)
  virtual double stepBudget() const { return std::numeric_limits<double>::infinity(); }
};

/// Runs the loop until the platform stops or `frames` frames were drawn; returns the frames drawn.
int runAppLoop(AppSession& session, AppPlatform& platform, std::optional<int> frames);

}  // namespace fp::engine
