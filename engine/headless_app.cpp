#include "engine/headless_app.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <ostream>

#include "engine/headless_render.h"

namespace fp::engine {

struct HeadlessPlatform::Impl {
  std::unique_ptr<HeadlessRender> render;
};

HeadlessPlatform::HeadlessPlatform(const CliOptions& options) : m_impl(std::make_unique<Impl>()) {
  if (options.render)
    m_impl->render = std::make_unique<HeadlessRender>(options);
}

HeadlessPlatform::~HeadlessPlatform() = default;

void HeadlessPlatform::input(AppSession& session, double) {
  session.setHandTarget(session.handPose());
}

void HeadlessPlatform::capture(AppSession& session, int frame) {
  if (m_impl->render)
    m_impl->render->renderFrame(frame, session.simulation());
}

SessionConfig sessionConfigOf(const CliOptions& options) {
  SessionConfig c;
  c.scenePath = options.scenePath;
  c.mode = options.mode;
  c.seed = options.seed;
  c.sets = options.sets;
  c.handScript = options.handScript;
  c.fixedStep = options.fixedStep;
  c.timeScale = options.timeScale;
  c.handScale = options.handScale;
  c.statePath = options.loadState;
  return c;
}

RunSummary runHeadlessApp(const CliOptions& options, std::ostream& out) {
  const int threads = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  SessionConfig config = sessionConfigOf(options);
  config.fixedStep = true;  // no wall clock without a window: every frame is 1 / frame_rate
  HeadlessPlatform platform(options);
  AppSession session(config);
  const sim::Simulation& simulation = session.simulation();
  double simTime = session.scene().simTime;
  if (options.simTime)
    simTime = *options.simTime;
  // a loaded state resumes at its frame: the run ends where the uninterrupted one would
  const int frames =
      (options.frames ? *options.frames : int(std::ceil(simTime * session.scene().frameRate - 1e-9))) -
      int(std::lround(simulation.time() * session.scene().frameRate));
  RunSummary s;
  s.scene = options.scenePath;
  s.mode = sim::modeName(simulation.mode());
  s.threads = threads;
  s.seed = simulation.params().seed;
  s.boundaryParticles = simulation.boundary().size();
  s.massInitial = simulation.totalMass();
  if (!options.quiet) {
    out << "scene " << session.scene().name << " (" << s.mode << ") with the hand replaying "
        << options.handScript << ": " << simulation.particles().size() << " fluid particles, "
        << simulation.boundary().size() << " boundary particles, " << threads << " threads, " << frames
        << " frames\n";
  }
  const auto start = std::chrono::steady_clock::now();
  s.frames = frames > 0 ? runAppLoop(session, platform, frames) : 0;
  s.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const sim::Simulation& sim = session.simulation();
  if (!session.error().empty()) {
    s.status = "unstable";
    s.message = session.error();
  } else if (!options.saveState.empty()) {
    session.saveState(options.saveState);
  }
  fillRunFigures(sim, s);
  return s;
}

}  // namespace fp::engine
