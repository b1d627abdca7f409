#include "engine/xr_app.h"

#include <csignal>
#include <fstream>
#include <thread>

#include "engine/app_loop.h"
#include "engine/cli_app.h"
#include "engine/headless_app.h"
#include "engine/headless_runner.h"
#include "engine/tracked_hands.h"
#include "engine/xr_program.h"
#include "input/joint_track.h"
#include "render/fluid_renderer.h"
#include "render/gl_api.h"
#include "render/shader_program.h"
// GLX and X11 last: their macros (Success, None) clash with Eigen
#include <GL/glx.h>
#include <X11/Xlib.h>

namespace fp::engine {

namespace {

/// simulated time within which the first tracked hand sizes the hands' colliders (the session starts over)
/// [s]
constexpr double kSizingWindow = 0.5;

volatile std::sig_atomic_t g_interrupted = 0;
void onInterrupt(int) {
  g_interrupted = 1;
}

/// A GLX 3.3 core context on a small pbuffer, current on this thread: what the session renders with when
/// there is no mirror window.
class GlxContext {
 public:
  GlxContext() {
    m_display = XOpenDisplay(nullptr);
    if (!m_display)
      throw XrUnavailable("no X display for the OpenXR GL (Xlib) session");
    const int attributes[] = {GLX_DRAWABLE_TYPE,
                              GLX_PBUFFER_BIT,
                              GLX_RENDER_TYPE,
                              GLX_RGBA_BIT,
                              GLX_RED_SIZE,
                              8,
                              GLX_GREEN_SIZE,
                              8,
                              GLX_BLUE_SIZE,
                              8,
                              GLX_DEPTH_SIZE,
                              24,
                              None};
    int count = 0;
    GLXFBConfig* configs = glXChooseFBConfig(m_display, DefaultScreen(m_display), attributes, &count);
    if (!configs || count == 0)
      throw XrUnavailable("no GLX framebuffer configuration");
    m_config = configs[0];
    XFree(configs);
    using CreateContext = GLXContext (*)(Display*, GLXFBConfig, GLXContext, Bool, const int*);
    const auto create =
        reinterpret_cast<CreateContext>(render::gl::glxProcAddress("glXCreateContextAttribsARB"));
    for (int minor : {5, 3}) {
      const int ca[] = {GLX_CONTEXT_MAJOR_VERSION_ARB,
                        minor == 5 ? 4 : 3,
                        GLX_CONTEXT_MINOR_VERSION_ARB,
                        minor,
                        GLX_CONTEXT_PROFILE_MASK_ARB,
                        GLX_CONTEXT_CORE_PROFILE_BIT_ARB,
                        None};
      if (!m_context && create)
        m_context = create(m_display, m_config, nullptr, True, ca);
    }
    const int pb[] = {GLX_PBUFFER_WIDTH, 16, GLX_PBUFFER_HEIGHT, 16, None};
    m_pbuffer = glXCreatePbuffer(m_display, m_config, pb);
    if (!m_context || !m_pbuffer || !glXMakeContextCurrent(m_display, m_pbuffer, m_pbuffer, m_context))
      throw XrUnavailable("no GLX OpenGL 3.3 core context for the OpenXR session");
    render::gl::loadFunctions(&render::gl::glxProcAddress);
  }
  ~GlxContext() {
    glXMakeContextCurrent(m_display, None, None, nullptr);
    if (m_context)
      glXDestroyContext(m_display, m_context);
    if (m_pbuffer)
      glXDestroyPbuffer(m_display, m_pbuffer);
    XCloseDisplay(m_display);
  }
  GlxBinding binding() const { return {m_display, m_config, m_pbuffer, m_context}; }

 private:
  Display* m_display = nullptr;
  GLXFBConfig m_config = nullptr;
  GLXPbuffer m_pbuffer = 0;
  GLXContext m_context = nullptr;
};

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
  XrPlatform(const CliOptions& options, XrProgram& xr, GlxContext& gl)
      : m_options(options),
        m_xr(xr),
        m_gl(gl),
        m_renderer(options.shaderDir.empty() ? render::defaultShaderDir() : options.shaderDir) {
    m_renderer.settings().showSpray = false;
  }

  bool running() override { return !m_exit; }

  FrameClock beginFrame() override {
    if (g_interrupted && !m_exitRequested) {
      m_xr.requestExit();
      m_exitRequested = true;
    }
    m_frameActive = false;
    FrameClock idle;
    idle.simulate = false;
    idle.render = false;
    const XrLifecycle l = m_xr.pollEvents();
    if (l == XrLifecycle::Exit) {
      m_exit = true;
      return idle;
    }
    if (l == XrLifecycle::Recreate) {
      idle.restart = true;
      return idle;
    }
    if (l == XrLifecycle::Idle) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // nothing to show: do not spin
      return idle;
    }
    // xrWaitFrame: the frame's time is the predicted display period; the last frame's steps run meanwhile
    m_timing = m_xr.beginFrame();
    m_frameActive = true;
    FrameClock clock;
    clock.dt = m_timing.period;
    clock.simulate = true;
    clock.render = true;  // draw() ends every begun frame, with no layer when the session is not visible
    return clock;
  }

  void restart(AppSession&) override {
    m_xr.createSession(m_gl.binding());
    ++m_recreated;
  }

  void input(AppSession& session, const FrameClock&) override {
    if (!m_frameActive)
      return;
    if (!m_placed) {
      const auto [head, turn] = m_xr.headPose();
      m_placement.place(head, turn, m_xr.stageSpace());
      m_placed = true;
    }
    const XrHands hands = m_xr.locateHands();
    if (hands.recentre) {
      const auto [head, turn] = m_xr.headPose();
      m_placement.place(head, turn, m_xr.stageSpace());
    }
    TrackedJoints joints;
    for (std::size_t k = 0; k < joints.size(); ++k) {
      if (hands.joints[k])
        joints[k] = m_placement.toScene(*hands.joints[k]);
    }
    if (!m_sized) {
      // the hands' colliders take the tracked hands' sizes from the first frame one is seen in, while the
      // water has barely started (the session starts over)
      const bool tracked = joints[0] || joints[1];
      if (tracked && !hands.fromControllers)
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

  void capture(AppSession& session, int) override {
    if (m_frameActive && m_timing.shouldRender)
      m_renderer.update(render::frameDataOf(session.simulation()));
  }

  void draw(AppSession&, int) override {
    if (!m_frameActive)
      return;
    const float nearZ = 0.05f, farZ = 50.0f;
    if (m_timing.shouldRender) {
      const auto eyes = m_xr.locateEyes();
      const render::Mat4 model = m_placement.sceneToSpace();
      for (int eye = 0; eye < 2; ++eye) {
        render::RenderTarget target;
        target.framebuffer = m_xr.acquireEye(eye);
        target.width = eyes[eye].width;
        target.height = eyes[eye].height;
        m_renderer.renderView(eyes[eye].view * model, render::offAxisPerspective(eyes[eye].fov, nearZ, farZ),
                              target);
        m_xr.releaseEye(eye);
      }
    }
    m_xr.endFrame(m_timing.shouldRender, nearZ, farZ);
    ++m_submitted;
  }

  /// the steps must leave the frame's display period to the drawing: most of a period, never more
  double stepBudget() const override { return m_frameActive ? 0.6 * m_timing.period : 0.0; }

  void finish() {
    if (!m_options.recordHands.empty())
      m_recording.save(m_options.recordHands);
  }
  int submitted() const { return m_submitted; }
  int recreated() const { return m_recreated; }

  TankPlacement m_placement;

 private:
  const CliOptions& m_options;
  XrProgram& m_xr;
  GlxContext& m_gl;
  render::FluidRenderer m_renderer;
  XrProgram::FrameTiming m_timing;
  bool m_frameActive = false;
  bool m_exit = false;
  bool m_exitRequested = false;
  bool m_placed = false;
  int m_submitted = 0;
  int m_recreated = 0;
  input::JointTrack m_recording;
  bool m_sized = false;
};

}  // namespace

int runXrApp(const CliOptions& options, std::ostream& out) {
  XrProgram xr("fluidplaying");
  GlxContext gl;
  xr.createSession(gl.binding());
  SessionConfig config = sessionConfigOf(options);
  config.hand = false;       // the tracked hands take the mouse hand's place
  AppSession probe(config);  // the scene, for the tank's floor centre and the hands' resting pose
  sim::Aabb water;
  for (const sim::FluidBlock& b : probe.scene().fluid)
    water.extend(b.box);
  AppSession& session = probe;
  attachTrackedHands(session, {}, options.handScale);  // the model hand until a tracked one is seen
  XrPlatform platform(options, xr, gl);
  platform.m_placement.floorCentre =
      water.isEmpty() ? sim::Vec3d::Zero()
                      : sim::Vec3d(water.center().x(), water.min().y(), water.center().z());
  if (!options.quiet) {
    out << "headset " << xr.description() << " (" << xr.recommendedSize()[0] << "x" << xr.recommendedSize()[1]
        << " per eye, " << (xr.stageSpace() ? "STAGE" : "LOCAL") << " space); scene " << session.scene().name
        << ", " << session.simulation().particles().size() << " particles\n";
  }
  g_interrupted = 0;
  auto previous = std::signal(SIGINT, onInterrupt);
  const int frames = runAppLoop(session, platform, options.frames);
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
    out << "frames " << frames << ", submitted " << platform.submitted() << ", sessions recreated "
        << platform.recreated() << ", simulated " << session.simulation().time() << " s\n";
  }
  return kExitOk;
}

}  // namespace fp::engine
