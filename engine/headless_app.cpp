#include "engine/headless_app.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <ostream>

#include "input/joint_track.h"
#include "sim/metrics.h"
#include "sim/ply_writer.h"

namespace fp::engine {

namespace {
using Clock = std::chrono::steady_clock;
/// the paper's splash height: the height below which 99.9 % of the mass lies, above its value at rest
constexpr double kSplashHeightFraction = 0.999;
}  // namespace

HeadlessPlatform::HeadlessPlatform(const CliOptions& options, double frameRate, double endTime,
                                   RunSummary& summary, std::ostream& progress, FrameCallback onFrame)
    : m_options(options),
      m_frameDt(1.0 / frameRate),
      m_endTime(endTime),
      m_frameCount(int(std::ceil(endTime * frameRate - 1e-9))),
      m_summary(summary),
      m_progress(progress),
      m_onFrame(std::move(onFrame)) {}

FrameClock HeadlessPlatform::beginFrame() {
  FrameClock clock;
  clock.dt = m_frameDt;
  clock.simulate = m_loopFrames++ < m_frameCount;
  return clock;
}

void HeadlessPlatform::input(AppSession& session, const FrameClock&) {
  session.setHandTarget(session.handPose());  // the hand rests, or the replay moves it
}

double HeadlessPlatform::wallSeconds() const {
  return std::chrono::duration<double>(Clock::now() - m_start).count();
}

void HeadlessPlatform::capture(AppSession& session, int frame) {
  const sim::Simulation& simulation = session.simulation();
  if (!session.error().empty()) {
    m_summary.status = "unstable";
    m_summary.message = session.error();
    m_done = true;
    return;
  }
  // a frame is taken when the steps reached its end (a shorter last frame is not)
  if (frame == 0 || simulation.time() >= m_startTime + (m_frame + 1) * m_frameDt - 1e-12)
    takeFrame(simulation);
  if (frame == 0)
    m_start = m_lastReport = Clock::now();
  if (frame >= m_frameCount) {
    m_done = true;
    return;
  }
  const auto now = Clock::now();
  if (!m_options.quiet && std::chrono::duration<double>(now - m_lastReport).count() > 2.0) {
    m_lastReport = now;
    const double wall = std::chrono::duration<double>(now - m_start).count();
    const double done = simulation.time() - m_startTime;
    const double eta = done > 0.0 ? wall / done * (m_endTime - done) : 0.0;
    m_progress << std::fixed << std::setprecision(3) << "  t = " << simulation.time() << " / "
               << m_startTime + m_endTime << " s, step " << simulation.stepCount() << ", "
               << simulation.particles().size() << " particles, wall " << std::setprecision(1) << wall
               << " s, eta " << eta << " s\n"
               << std::defaultfloat << std::flush;
  }
}

void HeadlessPlatform::takeFrame(const sim::Simulation& simulation) {
  ++m_frame;
  if (!m_options.exportDir.empty()) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.ply", m_frame);
    sim::writePly((std::filesystem::path(m_options.exportDir) / name).string(), simulation.particles());
  }
  const sim::SplashParticles& sp = m_splash.generate(simulation, std::uint64_t(m_frame));
  const double h = sim::heightPercentile(simulation.particles(), kSplashHeightFraction);
  const double hs = sim::heightPercentile(simulation.particles(), kSplashHeightFraction, &sp,
                                          simulation.params().splashCount);
  if (m_frame == 0)
    m_restHeight = h;
  RunSummary& s = m_summary;
  s.splashParticles += double(sp.size());
  s.splashHeight += h - m_restHeight;
  s.splashHeightWithSplash += hs - m_restHeight;
  s.splashHeightMax = std::max(s.splashHeightMax, h - m_restHeight);
  s.splashHeightWithSplashMax = std::max(s.splashHeightWithSplashMax, hs - m_restHeight);
  if (m_onFrame)
    m_onFrame(m_frame, simulation, sp);
}

SessionConfig sessionConfigOf(const CliOptions& options) {
  SessionConfig c;
  c.scenePath = options.scenePath;
  c.mode = options.mode;
  c.seed = options.seed;
  c.sets = options.sets;
  c.handScript = options.handScript;
  if (input::JointTrack::isJointFile(c.handScript)) {
    c.handScript.clear();  // a joint recording: the tracked hands replay it (engine/tracked_hands.h)
    c.hand = false;
  }
  c.fixedStep = options.fixedStep;
  c.timeScale = options.timeScale;
  c.handScale = options.handScale;
  c.loadState = options.loadState;
  c.saveState = options.saveState;
  c.saveStateEvery = options.saveStateEvery;
  c.recover = !options.headless;  // the window and the headset roll back; a headless run reports and ends
  c.slowSteps = options.slowSteps;
  c.slowStepSeconds = 1e-3 * options.slowStepMs;
  return c;
}

}  // namespace fp::engine
