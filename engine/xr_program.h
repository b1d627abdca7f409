#pragma once
/// The OpenXR side of the headset mode, after hello_xr's split (OpenXR-SDK-Source src/tests/hello_xr): the
/// instance, system and GL session, the reference space, per-eye swapchains, the frame calls, the session
/// lifecycle, and the hands (XR_EXT_hand_tracking, or controllers through an action set). It hands out the
/// project's own types (input::HandJoints, render matrices); no OpenXR type leaves engine/xr_program.cpp.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "engine/gl_window.h"  // GlxBinding: the context the session renders with (the mirror window's)
#include "input/joint_hand.h"
#include "render/camera.h"

namespace fp::engine {

/// The headset cannot be used: the message is one line naming what is missing (no runtime, no HMD, no GL).
class XrUnavailable : public std::runtime_error {
 public:
  explicit XrUnavailable(const std::string& what) : std::runtime_error(what) {}
};

/// One eye of a frame.
struct XrEyeView {
  render::Mat4 view = render::Mat4::Identity();  ///< world (the reference space) -> eye
  render::FieldOfView fov;                       ///< the eye's asymmetric field of view
  Eigen::Vector3f position{0.0f, 0.0f, 0.0f};    ///< eye position in the reference space [m]
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();  ///< eye -> reference space
  int width = 0;                                                    ///< swapchain image size [px]
  int height = 0;                                                   ///< [px]
};

/// What pollEvents asks the caller to do.
enum class XrLifecycle {
  Idle,      ///< no frames now (not yet READY, or stopped): poll again later
  Running,   ///< run frames
  Recreate,  ///< the session was lost (LOSS_PENDING) and destroyed: create a new one
  Exit,      ///< the session ended (EXITING) or the instance is lost: quit
};

/// Both hands as the runtime reports them this frame, in the reference space.
struct XrHands {
  std::array<std::optional<input::HandJoints>, 2> joints;  ///< by input::HandSide; empty when not tracked
  bool fromControllers = false;                            ///< controller poses, not tracked joints
  bool recentre = false;                                   ///< the menu button was pressed this frame
};

/// The connection to an OpenXR runtime and its session.
class XrProgram {
 public:
  /// Instance (XR_KHR_opengl_enable required; XR_EXT_hand_tracking and XR_KHR_composition_layer_depth when
  /// offered) and the HMD system. Throws XrUnavailable.
  explicit XrProgram(const std::string& appName);
  ~XrProgram();
  XrProgram(const XrProgram&) = delete;
  XrProgram& operator=(const XrProgram&) = delete;

  /// runtime and system names, "FluidPlaying test runtime, FluidPlaying test HMD"
  const std::string& description() const { return m_description; }
  /// the recommended per-eye image size [px]
  std::array<int, 2> recommendedSize() const;
  /// the OpenGL version range the runtime accepts, "3.3 - 4.6"
  std::string glRequirement() const;

  /// Creates the session on `binding`'s context, which must be current (and stay current for every call
  /// below): reference space (STAGE, LOCAL where there is none), swapchains (sRGB colour preferred, depth
  /// when offered), actions and hand trackers. Throws XrUnavailable.
  void createSession(const GlxBinding& binding);
  /// true while a session exists
  bool hasSession() const;
  /// true between xrBeginSession and xrEndSession (the session may be asked to exit)
  bool sessionRunning() const;
  /// the reference space is STAGE (false: LOCAL)
  bool stageSpace() const;
  /// Polls the runtime's events and follows the lifecycle: begins the session on READY, ends it on STOPPING,
  /// destroys it on LOSS_PENDING (Recreate) and on EXITING (Exit).
  XrLifecycle pollEvents();
  /// asks the runtime to end the session (Ctrl+C, the mirror window closed); pollEvents then winds it down
  void requestExit();

  /// Frame timing of xrWaitFrame.
  struct FrameTiming {
    std::int64_t displayTime = 0;  ///< predicted display time [ns, runtime clock]
    double period = 0.0;           ///< predicted display period [s]
    bool shouldRender = false;     ///< the session is visible
  };
  /// xrWaitFrame (blocks until the frame may start), then xrBeginFrame
  FrameTiming beginFrame();
  /// the eyes at the frame's display time
  std::array<XrEyeView, 2> locateEyes();
  /// Acquires eye `eye`'s images and returns a framebuffer with them attached (colour, and depth: the depth
  /// swapchain's image or a renderbuffer); draw, then call releaseEye.
  unsigned acquireEye(int eye);
  /// releases the eye's images
  void releaseEye(int eye);
  /// xrEndFrame: the projection layer of both eyes when `rendered`, no layer otherwise
  void endFrame(bool rendered, float nearZ, float farZ);
  /// the hands at the frame's display time (call after beginFrame)
  XrHands locateHands();
  /// the head's pose in the reference space at the frame's display time (position [m], head -> space)
  std::pair<Eigen::Vector3f, Eigen::Quaternionf> headPose();

 private:
  struct Impl;
  std::unique_ptr<Impl> m;
  std::string m_description;
};

}  // namespace fp::engine
