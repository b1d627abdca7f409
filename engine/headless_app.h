#pragma once
/// The headless platform of the app loop: no window and no wall clock. Every frame advances one frame of the
/// scene (fixed steps) up to the run's end; the hand rests or follows a recorded replay (--hand-script). Each
/// frame it takes from the idle simulation the run's figures (splash and the height the water reaches), the
/// PLY export and the frame callback (the headless renderer), so a headless run steps the simulation through
/// the same loop as the window and the headset.

#include <chrono>
#include <iosfwd>
#include <string>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/headless_runner.h"
#include "sim/splash.h"

namespace fp::engine {

/// Platform with no window: fixed frame steps until `endTime`, with per-frame figures, export and callback.
class HeadlessPlatform : public AppPlatform {
 public:
  /// Runs frames of 1 / frameRate simulated seconds until `endTime` [s] (the last frame may be shorter);
  /// writes the figures into `summary`, progress lines to `progress` unless options.quiet, PLY files into
  /// options.exportDir when set, and calls `onFrame` with every frame (frame 0 is the initial state).
  HeadlessPlatform(const CliOptions& options, double frameRate, double endTime, RunSummary& summary,
                   std::ostream& progress, FrameCallback onFrame = {});
  bool running() override { return !m_done; }
  FrameClock beginFrame() override;
  void input(AppSession& session, const FrameClock& clock) override;
  void capture(AppSession& session, int frame) override;
  void draw(AppSession&, int) override {}

  /// the run starts at simulated time `t` [s] (a loaded state); frames and `endTime` count from there
  void setStartTime(double t) { m_startTime = t; }
  /// frames the run completed after the initial state
  int frames() const { return m_frame; }
  /// wall time since the initial state was taken [s]
  double wallSeconds() const;

 private:
  void takeFrame(const sim::Simulation& simulation);

  const CliOptions& m_options;
  double m_frameDt;
  double m_endTime;
  double m_startTime = 0.0;
  int m_frameCount;  // frames with steps: the last frame only takes the final state
  RunSummary& m_summary;
  std::ostream& m_progress;
  FrameCallback m_onFrame;
  sim::SplashGenerator m_splash;
  double m_restHeight = 0.0;
  int m_frame = -1;  // the last frame taken
  int m_loopFrames = 0;
  bool m_done = false;
  std::chrono::steady_clock::time_point m_start;
  std::chrono::steady_clock::time_point m_lastReport;
};

/// The session settings of the command line.
SessionConfig sessionConfigOf(const CliOptions& options);

}  // namespace fp::engine
