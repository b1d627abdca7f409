#pragma once
/// The app loop with no window: a recorded hand (--hand-script) replayed against a scene in fixed frame
/// steps, optionally rendered to PNG through OSMesa. It is the desktop app's loop with headless edges, so a
/// replayed interaction runs the same code in the window, in tests, in benchmarks and for videos.

#include <iosfwd>

#include "engine/app_loop.h"
#include "engine/cli.h"
#include "engine/headless_runner.h"

namespace fp::engine {

/// Platform with no window: the hand follows the replay; with --render every frame is written as PNG.
class HeadlessPlatform : public AppPlatform {
 public:
  /// Creates the offscreen renderer when options.render is set (throws like HeadlessRender).
  explicit HeadlessPlatform(const CliOptions& options);
  ~HeadlessPlatform() override;
  bool running() override { return true; }
  void input(AppSession& session, double wallDt) override;
  void capture(AppSession& session, int frame) override;
  void draw(AppSession&, int) override {}

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// Runs `options` (headless, with a hand script) through the app loop in fixed steps and returns the summary
/// the headless runner would give. Throws sim::InputError for a bad scene or hand script.
RunSummary runHeadlessApp(const CliOptions& options, std::ostream& out);

/// The session settings of the command line.
SessionConfig sessionConfigOf(const CliOptions& options);

}  // namespace fp::engine
