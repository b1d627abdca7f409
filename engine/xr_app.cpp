#include "engine/xr_app.h"

#include <csignal>
#include <fstream>
#include <thread>

#include <chrono>
#include <memory>

#include "engine/app_loop.h"
#include "engine/cli_app.h"
#include "engine/gl_window.h"
#include "engine/headless_app.h"
#include "engine/headless_runner.h"
#include "engine/tracked_hands.h"
#include "engine/xr_mirror.h"
#include "engine/xr_program.h"
#include "input/joint_track.h"
#include "render/fluid_renderer.h"
#include "render/gl_api.h"
#include "render/shader_program.h"

namespace fp::engine {

namespace {

/// simulated time within which the first tracked hand sizes the hands' colliders (the session starts over)
/// [s]
constexpr double kSizingWindow = 0.5;

volatile std::sig_atomic_t g_interrupted = 0;
void onInterrupt(int) {
  g_interrupted = 1;
}

/// The context the session renders in: the mirror window's (a display and no --no-window), else a hidden
/// window's. No display: the headset mode cannot run (XrUnavailable).
std::unique_ptr<GlWindow> openContext(const CliOptions& options, bool visible) {
  GlWindowOptions w;
  w.width = options.sizeGiven ? options.width : 960;
  w.height = options.sizeGiven ? options.height : 540;
  w.visible = visible;
  w.title = "FluidPlaying (headset mirror)";
  w.swapInterval = 0;  // xrWaitFrame paces the frames, never the desktop display
  try {
    return std::make_unique<GlWindow>(w);
  } catch (const WindowUnavailable& e) {
    throw XrUnavailable(std::string("no X display for the OpenXR GL (Xlib) session: ") + e.what());
  }
}

/// Scene <-> reference space: the tank's floor centre on a table 0.5 m in front of the head, facing it.
struct TankPlacement {
  sim::Quatd turn = sim::Quatd::Identity();  // scene -> space
  sim::Vec3d anchor = sim::Vec3d::Zero();    // where the scene's floor centre is in the space
  sim::Vec3d floorCentre = sim::Vec3d::Zero();

  void place(const Eigen::Vector3f& head, const Eigen::Quaternionf& headTurn, bool stage) {
    // the head's yaw only: the tank stays level
    const sim::Vec3d forward = (headTurn.cast<double>() * sim::Vec3d(0, 0, -1));
    const double yaw = std::atan2(-forward.x(), -forward.z());
    turn = sim::Quatd(Eigen::AngleAxisd(yaw, sim::Vec3d::UnitY()));
    anchor = head.cast<double>() + turn * sim::Vec3d(0, 0, -0.5);
    anchor.y() = stage ? 0.75 : head.y() - 0.85;  // table height: on the STAGE floor, or below the LOCAL head
  }
  sim::Vec3d toScene(const sim::Vec3d& p) const { return floorCentre + turn.conjugate() * (p - anchor); }
  render::Mat4 sceneToSpace() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.block<3, 3>(0, 0) = turn.toRotationMatrix();
    m.block<3, 1>(0, 3) = anchor - turn * floorCentre;
    return m.cast<float>();
  }
  input::HandJoints toScene(input::HandJoints j) const {
    for (input::JointPose& p : j.joint) {
      p.position = toScene(p.position);
      p.orientation = (turn.conjugate() * p.orientation).normalized();
    }
    return j;
  }
};

class XrPlatform : public AppPlatform {
 public:
  XrPlatform(const CliOptions& options, XrProgram& xr, GlWindow& gl, XrMirror* mirror)
      : m_options(options),
        m_xr(xr),
        m_gl(gl),
        m_mirror(mirror),
        m_renderer(options.shaderDir.empty() ? render::defaultShaderDir() : options.shaderDir) {
    m_renderer.settings().showSpray = false;
  }

  bool running() override { return !m_exit; }

  FrameClock beginFrame() override {
    m_frameActive = false;
    FrameClock idle;
    idle.simulate = false;
    idle.render = false;
    if (wantsExit())
      return idle;
    const XrLifecycle l = m_xr.pollEvents();
    if (l == XrLifecycle::Exit || (l == XrLifecycle::Recreate && m_exitRequested)) {
      m_exit = true;
      return idle;
    }
    if (l == XrLifecycle::Recreate) {
      idle.restart = true;
      return idle;
    }
    if (l == XrLifecycle::Idle) {
      // nothing to show in the headset: do not spin; the mirror still shows its last image and the panel
      std::this_thread::sleep_for(std::chrono::milliseconds(m_mirror ? 10 : 5));
      idle.render = m_mirror != nullptr;
      return idle;
    }
    // xrWaitFrame: the frame's time is the predicted display period; the last frame's steps run meanwhile
    m_timing = m_xr.beginFrame();
    m_frameActive = true;
    FrameClock clock;
    clock.dt = m_timing.period;
    clock.simulate = true;
    clock.render = true;  // draw() ends every begun frame, with no layer when the session is not visible
    // the display's deadline first: while the last steps still run the frame shows the last state again
    clock.waitForSteps = false;
    return clock;
  }

  void restart(AppSession&) override {
    m_xr.createSession(m_gl.glxBinding());
    ++m_recreated;
  }

  void input(AppSession& session, const FrameClock& clock) override {
    if (m_mirror && clock.render) {
      m_mirror->input(session, m_renderer.settings());
      m_recentre = m_mirror->takeRecentre() || m_recentre;
    }
    if (!m_frameActive)
      return;
    if (!m_placed) {
      const auto [head, turn] = m_xr.headPose();
      m_placement.place(head, turn, m_xr.stageSpace());
      m_placed = true;
    }
    const TrackedJoints joints = trackHands();
    if (!m_sized) {
      // the hands' colliders take the tracked hands' sizes from the first frame one is seen in, while the
      // water has barely started (the session starts over)
      const bool tracked = joints[0] || joints[1];
      if (tracked && !m_fromControllers)
        attachTrackedHands(session, joints, m_options.handScale);
      m_sized = tracked || session.simulation().time() > kSizingWindow;
    }
    // the hands ease in simulated time: a fixed-step frame is one frame of the scene
    setTrackedTargets(session, joints, session.fixedStep ? 1.0 / session.scene().frameRate : m_timing.period);
    if (!m_options.recordHands.empty()) {
      // at the simulated time of the frame, where a replay (engine/tracked_hands.h) looks for it
      input::JointFrame record;
      record.time = session.simulation().time();
      for (std::size_t k = 0; k < joints.size(); ++k) {
        if (joints[k])
          record.hands[k] = *joints[k];
      }
      m_recording.put(record);
    }
  }

  /// a frame drawn while the last steps still run: the hands' targets are queued for the next steps (they
  /// pass through every frame's); the mirror's window stays responsive, its panel waits for the steps
  void inputWhileStepping(AppSession& session, const FrameClock&) override {
    if (m_mirror)
      m_mirror->pollEvents();
    if (!m_frameActive || !m_placed)
      return;
    const TrackedJoints joints = trackHands();
    if (m_sized)
      setTrackedTargets(session, joints, m_timing.period);
  }

  void capture(AppSession& session, int) override {
    // also when the session is not visible: a frame drawn while the steps run shows the last state taken
    if (m_frameActive) {
      m_renderer.update(render::frameDataOf(session.simulation()));
      ++m_captured;
    }
  }

  void draw(AppSession& session, int frame) override {
    if (m_frameActive) {
      const float nearZ = 0.05f, farZ = 50.0f;
      if (m_timing.shouldRender) {
        const auto eyes = m_xr.locateEyes();
        const render::Mat4 model = m_placement.sceneToSpace();
        for (int eye = 0; eye < 2; ++eye) {
          render::RenderTarget target;
          target.framebuffer = m_xr.acquireEye(eye);
          target.width = eyes[eye].width;
          target.height = eyes[eye].height;
          m_renderer.renderView(eyes[eye].view * model,
                                render::offAxisPerspective(eyes[eye].fov, nearZ, farZ), target);
          if (eye == 0 && m_mirror)
            m_mirror->copyEye(target.framebuffer, target.width, target.height);
          m_xr.releaseEye(eye);
        }
      }
      m_xr.endFrame(m_timing.shouldRender, nearZ, farZ);
      ++m_submitted;
    }
    if (m_mirror)
      m_mirror->present(session, frame);
  }

  /// the steps must leave the frame's display period to the drawing: most of a period, never more
  double stepBudget() const override { return m_frameActive ? 0.6 * m_timing.period : 0.0; }

  void finish() {
    if (!m_options.recordHands.empty())
      m_recording.save(m_options.recordHands);
    if (m_mirror)
      m_mirror->finish();
  }
  /// asks the session to end, as Ctrl+C does (the end of --frames)
  void requestExit() { m_exitAsked = true; }
  int submitted() const { return m_submitted; }
  /// frames that took a new state to draw (the others drew the last one again while the steps ran)
  int captured() const { return m_captured; }
  int recreated() const { return m_recreated; }

  TankPlacement m_placement;

 private:
  /// Ctrl+C or the mirror closed: asks the runtime to end a running session (which the loop then follows
  /// through STOPPING to EXITING); true when there is no running session to wait for, and the loop stops
  bool wantsExit() {
    using Clock = std::chrono::steady_clock;
    const bool asked = g_interrupted || m_exitAsked || (m_mirror && m_mirror->closeRequested());
    if (asked && !m_exitRequested) {
      m_exitRequested = true;
      m_exitDeadline = Clock::now() + std::chrono::seconds(5);
      if (!m_xr.sessionRunning()) {
        m_exit = true;
        return true;
      }
      m_xr.requestExit();
    }
    if (m_exitRequested && Clock::now() > m_exitDeadline) {
      m_exit = true;  // a runtime that never ends the session does not keep the app open
      return true;
    }
    return false;
  }

  /// the frame's hands in the scene's frame; the menu button or the panel's Recentre moves the tank first
  TrackedJoints trackHands() {
    const XrHands hands = m_xr.locateHands();
    if (hands.recentre || m_recentre) {
      const auto [head, turn] = m_xr.headPose();
      m_placement.place(head, turn, m_xr.stageSpace());
      m_recentre = false;
    }
    m_fromControllers = hands.fromControllers;
    TrackedJoints joints;
    for (std::size_t k = 0; k < joints.size(); ++k) {
      if (hands.joints[k])
        joints[k] = m_placement.toScene(*hands.joints[k]);
    }
    return joints;
  }

  const CliOptions& m_options;
  XrProgram& m_xr;
  GlWindow& m_gl;
  XrMirror* m_mirror;
  render::FluidRenderer m_renderer;
  XrProgram::FrameTiming m_timing;
  bool m_frameActive = false;
  bool m_fromControllers = false;
  int m_captured = 0;
  bool m_exit = false;
  bool m_exitAsked = false;
  bool m_exitRequested = false;
  std::chrono::steady_clock::time_point m_exitDeadline;
  bool m_placed = false;
  bool m_recentre = false;
  int m_submitted = 0;
  int m_recreated = 0;
  input::JointTrack m_recording;
  bool m_sized = false;
};

}  // namespace

int runXrApp(const CliOptions& options, std::ostream& out) {
  // declared first, so it goes last: the program destroys the session's GL objects in its context
  std::unique_ptr<GlWindow> gl;
  // the runtime first: without one the desktop fallback opens no window here
  XrProgram xr("fluidplaying");
  const bool mirrored = !options.noWindow && !options.headless;
  gl = openContext(options, mirrored);
  const GlxBinding binding = gl->glxBinding();
  if (!binding.display)
    throw XrUnavailable("the window's OpenGL context is not a GLX context (XR_KHR_opengl_enable needs Xlib)");
  xr.createSession(binding);
  SessionConfig config = sessionConfigOf(options);
  config.hand = false;       // the tracked hands take the mouse hand's place
  config.stepThread = true;  // the steps run while the eyes are drawn, and a frame may leave them running
  AppSession probe(config);  // the scene, for the tank's floor centre and the hands' resting pose
  sim::Aabb water;
  for (const sim::FluidBlock& b : probe.scene().fluid)
    water.extend(b.box);
  AppSession& session = probe;
  attachTrackedHands(session, {}, options.handScale);  // the model hand until a tracked one is seen
  std::unique_ptr<XrMirror> mirror;
  if (mirrored)
    mirror = std::make_unique<XrMirror>(*gl, options, options.frames);
  XrPlatform platform(options, xr, *gl, mirror.get());
  platform.m_placement.floorCentre =
      water.isEmpty() ? sim::Vec3d::Zero()
                      : sim::Vec3d(water.center().x(), water.min().y(), water.center().z());
  if (!options.quiet) {
    out << "headset " << xr.description() << " (" << xr.recommendedSize()[0] << "x" << xr.recommendedSize()[1]
        << " per eye, " << (xr.stageSpace() ? "STAGE" : "LOCAL") << " space); "
        << (mirrored ? "mirror window " : "hidden context ") << gl->description() << "; scene "
        << session.scene().name << ", " << session.simulation().particles().size() << " particles\n";
  }
  g_interrupted = 0;
  auto previous = std::signal(SIGINT, onInterrupt);
  const int frames = runAppLoop(session, platform, options.frames);
  if (platform.running()) {
    // --frames reached: the session still ends as the spec says, through STOPPING and EXITING
    platform.requestExit();
    runAppLoop(session, platform, std::nullopt);
  }
  std::signal(SIGINT, previous);
  platform.finish();
  if (!options.statsPath.empty()) {
    RunSummary summary;
    summary.scene = options.scenePath;
    summary.mode = sim::modeName(session.simulation().mode());
    summary.frames = frames;
    fillRunFigures(session.simulation(), summary);
    writeStatsJson(options.statsPath, summary);
  }
  if (!options.quiet) {
    out << "frames " << frames << ", submitted " << platform.submitted() << ", states taken "
        << platform.captured() << ", sessions recreated " << platform.recreated() << ", simulated "
        << session.simulation().time() << " s\n";
  }
  return kExitOk;
}

}  // namespace fp::engine
