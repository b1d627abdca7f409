// A small OpenXR runtime for the tests (never shipped): one HMD with two asymmetric views at a scripted head
// pose, GL (Xlib/GLX) swapchains created in the application's context, a frame loop with a fixed display
// period, hand joints played from a joint recording (input/joint_track.h's CSV), controllers, and the session
// state changes a test asks for. Misuse is answered with the error codes the OpenXR 1.0 specification gives.
// Loaded by the Khronos loader through its manifest (XR_RUNTIME_JSON); configured by environment variables,
// see tests/xr/runtime/README.md.
#include <GL/gl.h>
#include <GL/glx.h>
#include <X11/Xlib.h>

#define XR_NO_PROTOTYPES
#define XR_USE_GRAPHICS_API_OPENGL
#define XR_USE_PLATFORM_XLIB
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/xr/runtime/pose_math.h"

// The loader <-> runtime negotiation (loader_interfaces.h of the OpenXR SDK, not installed by Debian).
extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
};
struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};
struct XrNegotiateRuntimeRequest {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t runtimeInterfaceVersion;
  XrVersion runtimeApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};
}

namespace {

using fpxr::Pose;
using fpxr::Quat;
using fpxr::Vec;

// ---- configuration (environment) ----

std::string env(const char* name, const char* fallback = "") {
  const char* v = std::getenv(name);
  return v ? v : fallback;
}
bool envOn(const char* name) {
  return env(name) == "1";
}
std::vector<double> envNumbers(const char* name, const char* fallback) {
  std::vector<double> out;
  std::stringstream in(env(name, fallback));
  std::string item;
  while (std::getline(in, item, ','))
    out.push_back(std::atof(item.c_str()));
  return out;
}

struct Config {
  bool gl = !envOn("FP_XR_NO_GL");
  bool handTracking = !envOn("FP_XR_NO_HANDS");
  bool hmd = !envOn("FP_XR_NO_HMD");
  bool stage = !envOn("FP_XR_NO_STAGE");
  bool virtualTime = envOn("FP_XR_VIRTUAL_TIME");
  std::int64_t period = std::int64_t(envNumbers("FP_XR_PERIOD_NS", "11111111")[0]);
  std::vector<double> size = envNumbers("FP_XR_SIZE", "128,128");
  std::vector<double> formats =
      envNumbers("FP_XR_FORMATS", "35907,32856,33190,36012");        // sRGB8_A8, RGBA8, D24, D32F
  std::vector<double> head = envNumbers("FP_XR_HEAD", "0,1.6,0,0");  // stage x, y, z [m], yaw [deg]
  double ipd = envNumbers("FP_XR_IPD", "0.064")[0];
  std::vector<double> handOffset = envNumbers("FP_XR_HANDS_OFFSET", "0,0,0");
  std::vector<double> controllers = envNumbers("FP_XR_CONTROLLERS", "0,0");  // trigger, squeeze
  std::string hands = env("FP_XR_HANDS");
  std::string events = env("FP_XR_EVENTS");
  std::string stats = env("FP_XR_STATS");
  std::string frameLog = env("FP_XR_FRAME_LOG");  // a line per xrEndFrame: display time, end time [ns]
  bool frameHash = envOn("FP_XR_FRAME_HASH");     // the log's lines end with a hash of the left eye's image
  std::string capture =
      env("FP_XR_CAPTURE");  // "FRAME,DIR": the eyes of frame FRAME as DIR/eye0.ppm, eye1.ppm
  std::string profile = env("FP_XR_PROFILE", "/interaction_profiles/khr/simple_controller");
};

// ---- the joint recording ----

struct JointSample {
  bool valid = false;
  Pose pose[26];
  double radius[26] = {};
};
struct JointFrame {
  double time = 0.0;
  JointSample hand[2];
};

std::vector<JointFrame> loadJoints(const std::string& path, const Vec& offset) {
  std::vector<JointFrame> frames;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    if (line.empty())
      continue;
    std::stringstream row(line);
    std::string f[12];
    for (std::string& field : f)
      std::getline(row, field, ',');
    const double t = std::atof(f[0].c_str());
    if (frames.empty() || frames.back().time != t) {
      frames.emplace_back();
      frames.back().time = t;
    }
    JointFrame& frame = frames.back();
    const int h = f[1] == "left" ? 0 : 1;
    JointSample& s = frame.hand[h];
    int j = 0;
    while (j < 26 && s.radius[j] != 0.0)
      ++j;
    if (j >= 26)
      continue;
    s.valid = f[3] == "1";
    s.pose[j].p = Vec{std::atof(f[4].c_str()), std::atof(f[5].c_str()), std::atof(f[6].c_str())} + offset;
    s.pose[j].q = Quat{std::atof(f[7].c_str()), std::atof(f[8].c_str()), std::atof(f[9].c_str()),
                       std::atof(f[10].c_str())};
    s.radius[j] = std::atof(f[11].c_str());
  }
  return frames;
}

JointSample sampleJoints(const std::vector<JointFrame>& frames, int hand, double t) {
  if (frames.empty())
    return {};
  if (t <= frames.front().time)
    return frames.front().hand[hand];
  if (t >= frames.back().time)
    return frames.back().hand[hand];
  std::size_t i = 1;
  while (frames[i].time < t)
    ++i;
  const JointFrame& a = frames[i - 1];
  const JointFrame& b = frames[i];
  if (!a.hand[hand].valid || !b.hand[hand].valid)
    return a.hand[hand];
  const double u = (t - a.time) / (b.time - a.time);
  JointSample s = a.hand[hand];
  for (int j = 0; j < 26; ++j) {
    s.pose[j] = fpxr::interpolate(a.hand[hand].pose[j], b.hand[hand].pose[j], u);
    s.radius[j] = (1 - u) * a.hand[hand].radius[j] + u * b.hand[hand].radius[j];
  }
  return s;
}

// ---- objects ----

enum class Kind { Instance, Session, Space, Swapchain, ActionSet, Action, HandTracker };

struct Object {
  Kind kind;
  std::uint64_t parent = 0;
  virtual ~Object() = default;
  explicit Object(Kind k) : kind(k) {}
};

struct Instance : Object {
  static constexpr Kind kKind = Kind::Instance;
  Instance() : Object(Kind::Instance) {}
  bool glExt = false;
  bool handExt = false;
  bool depthExt = false;
  bool requirementsQueried = false;
  std::uint64_t session = 0;
  std::deque<XrEventDataBuffer> events;
  std::vector<std::string> paths{""};  // XrPath n is paths[n]
};

struct Session : Object {
  static constexpr Kind kKind = Kind::Session;
  Session() : Object(Kind::Session) {}
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;  // as the application has seen it
  bool running = false;
  bool exitRequested = false;
  bool waited = false;       // a frame was waited for and not begun
  bool begun = false;        // a frame was begun and not ended
  XrTime lastDisplay = 0;    // the last predicted display time handed out
  XrTime waitedDisplay = 0;  // of the frame waited for
  XrTime beginTime = 0;
  std::int64_t frame = 0;  // frames waited for
  bool attached = false;
  std::set<std::uint64_t> actionSets;
  bool lost[2] = {false, false};
  bool menu = false;
  std::vector<std::uint64_t> swapchains;
  XrTime waitCalled = 0, waitReturned = 0;  // the last xrWaitFrame [runtime clock]
};

struct Space : Object {
  static constexpr Kind kKind = Kind::Space;
  Space() : Object(Kind::Space) {}
  XrReferenceSpaceType type = XR_REFERENCE_SPACE_TYPE_VIEW;
  std::uint64_t action = 0;  // an action space
  int hand = -1;             // its subaction hand
  Pose offset;
};

struct Swapchain : Object {
  static constexpr Kind kKind = Kind::Swapchain;
  Swapchain() : Object(Kind::Swapchain) {}
  std::int64_t format = 0;
  std::uint32_t width = 0, height = 0;
  std::vector<GLuint> textures;
  std::deque<std::uint32_t> acquired;  // acquired, oldest first
  bool waited = false;                 // the oldest acquired image was waited for
  std::uint32_t next = 0;
  int released = -1;                      // the last released image
  XrTime acquiredAt = 0, releasedAt = 0;  // the last acquire and release [runtime clock]
};

struct ActionSet : Object {
  static constexpr Kind kKind = Kind::ActionSet;
  ActionSet() : Object(Kind::ActionSet) {}
  std::string name;
  bool attached = false;
};

struct Action : Object {
  static constexpr Kind kKind = Kind::Action;
  Action() : Object(Kind::Action) {}
  XrActionType type = XR_ACTION_TYPE_BOOLEAN_INPUT;
  std::string name;
  std::vector<XrPath> subactions;
  std::map<std::string, std::vector<std::string>> bindings;  // profile -> binding paths
};

struct HandTracker : Object {
  static constexpr Kind kKind = Kind::HandTracker;
  HandTracker() : Object(Kind::HandTracker) {}
  int hand = 0;
};

std::recursive_mutex g_mutex;
std::map<std::uint64_t, std::unique_ptr<Object>> g_objects;
std::uint64_t g_nextHandle = 0x1000;
Config* g_config = nullptr;
std::vector<JointFrame> g_joints;
std::int64_t g_startNs = 0;
struct Stats {
  long submitted = 0, waited = 0, missed = 0, sessions = 0, begun = 0, ended = 0, layers = 0;
  long instancesDestroyed = 0;  // xrDestroyInstance calls (the mirror tests check an orderly end)
} g_stats;

template <class T>
std::uint64_t handleOf(T h) {
  return std::uint64_t(reinterpret_cast<std::uintptr_t>(h));
}

template <class T>
T* lookup(std::uint64_t handle, Kind kind) {
  const auto it = g_objects.find(handle);
  if (it == g_objects.end() || it->second->kind != kind)
    return nullptr;
  return static_cast<T*>(it->second.get());
}

template <class T, class H>
H create(std::unique_ptr<T> object, std::uint64_t parent) {
  object->parent = parent;
  const std::uint64_t h = g_nextHandle++;
  g_objects[h] = std::move(object);
  return reinterpret_cast<H>(std::uintptr_t(h));
}

void destroyTree(std::uint64_t handle);

Instance* instanceOf(std::uint64_t handle) {
  Object* o = nullptr;
  while (handle) {
    const auto it = g_objects.find(handle);
    if (it == g_objects.end())
      return nullptr;
    o = it->second.get();
    if (o->kind == Kind::Instance)
      return static_cast<Instance*>(o);
    handle = o->parent;
  }
  return nullptr;
}

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
XrTime runtimeNow() {
  return XrTime(nowNs() - g_startNs + 1000000000LL);
}

void writeStats() {
  if (g_config->stats.empty())
    return;
  std::ofstream out(g_config->stats, std::ios::trunc);
  out << "submitted " << g_stats.submitted << "\nwaited " << g_stats.waited << "\nmissed " << g_stats.missed
      << "\nsessions " << g_stats.sessions << "\nbegun " << g_stats.begun << "\nended " << g_stats.ended
      << "\nlayers " << g_stats.layers << "\nperiod_ns " << g_config->period << "\n";
  out << "instances_destroyed " << g_stats.instancesDestroyed << "\n";
}

void queueState(Instance& inst, std::uint64_t session, XrSessionState state) {
  XrEventDataBuffer buffer{};
  auto* e = reinterpret_cast<XrEventDataSessionStateChanged*>(&buffer);
  e->type = XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED;
  e->session = reinterpret_cast<XrSession>(std::uintptr_t(session));
  e->state = state;
  e->time = runtimeNow();
  inst.events.push_back(buffer);
}

XrSessionState lastQueuedState(const Instance& inst, const Session& s) {
  XrSessionState st = s.state;
  for (const XrEventDataBuffer& b : inst.events) {
    if (b.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED)
      st = reinterpret_cast<const XrEventDataSessionStateChanged*>(&b)->state;
  }
  return st;
}

/// the runtime asks the session to stop: down through the states to STOPPING
void queueStop(Instance& inst, std::uint64_t sh, Session& s) {
  XrSessionState st = lastQueuedState(inst, s);
  if (st == XR_SESSION_STATE_FOCUSED) {
    queueState(inst, sh, XR_SESSION_STATE_VISIBLE);
    st = XR_SESSION_STATE_VISIBLE;
  }
  if (st == XR_SESSION_STATE_VISIBLE) {
    queueState(inst, sh, XR_SESSION_STATE_SYNCHRONIZED);
    st = XR_SESSION_STATE_SYNCHRONIZED;
  }
  if (st == XR_SESSION_STATE_SYNCHRONIZED || st == XR_SESSION_STATE_READY)
    queueState(inst, sh, XR_SESSION_STATE_STOPPING);
}

/// the scripted events of the frame just waited for ("FRAME:COMMAND,...", frames counted from 1 over all
/// sessions of the process): loss_pending, exit, lost_left, lost_right, track_left, track_right, menu
void runEvents(Instance& inst, std::uint64_t sh, Session& s) {
  std::stringstream in(g_config->events);
  std::string item;
  while (std::getline(in, item, ',')) {
    const std::size_t colon = item.find(':');
    if (colon == std::string::npos || std::atol(item.substr(0, colon).c_str()) != g_stats.waited)
      continue;
    const std::string cmd = item.substr(colon + 1);
    if (cmd == "loss_pending")
      queueState(inst, sh, XR_SESSION_STATE_LOSS_PENDING);
    else if (cmd == "exit")
      queueStop(inst, sh, s);
    else if (cmd == "lost_left" || cmd == "lost_right" || cmd == "track_left" || cmd == "track_right")
      s.lost[cmd.back() == 't' ? 1 : 0] = cmd.rfind("lost", 0) == 0;
    else if (cmd == "menu")
      s.menu = true;
  }
}

// ---- poses ----

Pose headPose() {
  const auto& h = g_config->head;
  return Pose{Quat::axisAngle(Vec{0, 1, 0}, h[3] * M_PI / 180.0), Vec{h[0], h[1], h[2]}};
}

/// the LOCAL space: at the head's starting position, gravity aligned, facing as the head
Pose localInStage() {
  const auto& h = g_config->head;
  return Pose{Quat::axisAngle(Vec{0, 1, 0}, h[3] * M_PI / 180.0), Vec{h[0], h[1], h[2]}};
}

double sessionSeconds(const Session& s, XrTime t) {
  return double(t - s.beginTime) * 1e-9;
}

/// the grip pose of controller `hand` in stage space, from the recorded palm (or a default in front)
bool gripPose(const Session& s, int hand, XrTime t, Pose& out) {
  if (s.lost[hand])
    return false;
  if (!g_joints.empty()) {
    const JointSample j = sampleJoints(g_joints, hand, sessionSeconds(s, t));
    if (!j.valid)
      return false;
    // the inverse of input/joint_hand's controllerHandPose: grip axes from the palm joint's frame
    const Quat toGrip = hand == 1 ? Quat::fromColumns(Vec{0, 1, 0}, Vec{-1, 0, 0}, Vec{0, 0, 1})
                                  : Quat::fromColumns(Vec{0, -1, 0}, Vec{1, 0, 0}, Vec{0, 0, 1});
    out = Pose{j.pose[0].q * toGrip, j.pose[0].p};
    return true;
  }
  out = Pose{Quat{}, Vec{hand == 0 ? -0.2 : 0.2, 1.0, -0.35}};
  return true;
}

bool spaceInStage(const Session& s, const Space& sp, XrTime t, Pose& out) {
  if (sp.action) {
    Pose grip;
    if (sp.hand < 0 || !gripPose(s, sp.hand, t, grip))
      return false;
    out = grip * sp.offset;
    return true;
  }
  switch (sp.type) {
    case XR_REFERENCE_SPACE_TYPE_VIEW:
      out = headPose() * sp.offset;
      return true;
    case XR_REFERENCE_SPACE_TYPE_LOCAL:
      out = localInStage() * sp.offset;
      return true;
    default:
      out = sp.offset;
      return true;
  }
}

XrPosef toXr(const Pose& p) {
  XrPosef x;
  x.orientation = {float(p.q.x), float(p.q.y), float(p.q.z), float(p.q.w)};
  x.position = {float(p.p.x), float(p.p.y), float(p.p.z)};
  return x;
}
Pose fromXr(const XrPosef& x) {
  return Pose{Quat{x.orientation.w, x.orientation.x, x.orientation.y, x.orientation.z}.normalized(),
              Vec{x.position.x, x.position.y, x.position.z}};
}
bool poseValid(const XrPosef& x) {
  const double n =
      std::sqrt(double(x.orientation.x) * x.orientation.x + double(x.orientation.y) * x.orientation.y +
                double(x.orientation.z) * x.orientation.z + double(x.orientation.w) * x.orientation.w);
  return std::abs(n - 1.0) < 1e-3;
}

// ---- GL, through glXGetProcAddressARB as real runtimes do ----

struct Gl {
  PFNGLGENTEXTURESEXTPROC genTextures = nullptr;
  void (*bindTexture)(GLenum, GLuint) = nullptr;
  void (*deleteTextures)(GLsizei, const GLuint*) = nullptr;
  void (*texStorage2D)(GLenum, GLsizei, GLenum, GLsizei, GLsizei) = nullptr;
  void (*getIntegerv)(GLenum, GLint*) = nullptr;
  void (*getTexImage)(GLenum, GLint, GLenum, GLenum, void*) = nullptr;
  GLboolean (*isTexture)(GLuint) = nullptr;
  void (*pixelStorei)(GLenum, GLint) = nullptr;
  void (*finish)() = nullptr;
  bool load() {
    auto get = [](const char* n) { return glXGetProcAddressARB(reinterpret_cast<const GLubyte*>(n)); };
    genTextures = reinterpret_cast<PFNGLGENTEXTURESEXTPROC>(get("glGenTextures"));
    bindTexture = reinterpret_cast<decltype(bindTexture)>(get("glBindTexture"));
    deleteTextures = reinterpret_cast<decltype(deleteTextures)>(get("glDeleteTextures"));
    texStorage2D = reinterpret_cast<decltype(texStorage2D)>(get("glTexStorage2D"));
    getIntegerv = reinterpret_cast<decltype(getIntegerv)>(get("glGetIntegerv"));
    getTexImage = reinterpret_cast<decltype(getTexImage)>(get("glGetTexImage"));
    isTexture = reinterpret_cast<decltype(isTexture)>(get("glIsTexture"));
    pixelStorei = reinterpret_cast<decltype(pixelStorei)>(get("glPixelStorei"));
    finish = reinterpret_cast<decltype(finish)>(get("glFinish"));
    return genTextures && bindTexture && deleteTextures && texStorage2D && getIntegerv && getTexImage &&
           isTexture && pixelStorei && finish;
  }
} g_gl;

// a colour swapchain image's RGBA pixels, bottom row first (the texture binding is restored)
std::vector<unsigned char> readImage(const Swapchain& sc, std::uint32_t image) {
  GLint bound = 0;
  g_gl.getIntegerv(GL_TEXTURE_BINDING_2D, &bound);
  g_gl.bindTexture(GL_TEXTURE_2D, sc.textures[image]);
  std::vector<unsigned char> pixels(std::size_t(sc.width) * sc.height * 4);
  g_gl.pixelStorei(GL_PACK_ALIGNMENT, 1);
  g_gl.getTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  g_gl.bindTexture(GL_TEXTURE_2D, GLuint(bound));
  return pixels;
}

void captureImage(const Swapchain& sc, std::uint32_t image, const XrRect2Di& rect, const std::string& path) {
  if (sc.format == 33190 || sc.format == 36012)
    return;
  const std::vector<unsigned char> pixels = readImage(sc, image);
  std::ofstream out(path, std::ios::binary);
  out << "P6\n" << rect.extent.width << " " << rect.extent.height << "\n255\n";
  // GL rows run bottom-up; the image file top-down
  for (int y = rect.offset.y + rect.extent.height - 1; y >= rect.offset.y; --y) {
    for (int x = rect.offset.x; x < rect.offset.x + rect.extent.width; ++x)
      out.write(reinterpret_cast<const char*>(&pixels[(std::size_t(y) * sc.width + x) * 4]), 3);
  }
}

// FNV-1a of a submitted colour image's pixels in `rect` (0 for a depth image)
std::uint64_t hashImage(const Swapchain& sc, std::uint32_t image, const XrRect2Di& rect) {
  if (sc.format == 33190 || sc.format == 36012)
    return 0;
  const std::vector<unsigned char> pixels = readImage(sc, image);
  std::uint64_t h = 1469598103934665603ull;
  for (int y = rect.offset.y; y < rect.offset.y + rect.extent.height; ++y) {
    for (int x = rect.offset.x; x < rect.offset.x + rect.extent.width; ++x) {
      for (int c = 0; c < 4; ++c)
        h = (h ^ pixels[(std::size_t(y) * sc.width + x) * 4 + c]) * 1099511628211ull;
    }
  }
  return h;
}

// ---- enumerations: the two-call idiom ----

template <class T, class Fill>
XrResult enumerate(std::uint32_t capacity, std::uint32_t* count, T* out, std::uint32_t n, Fill fill) {
  if (!count)
    return XR_ERROR_VALIDATION_FAILURE;
  *count = n;
  if (capacity == 0)
    return XR_SUCCESS;
  if (capacity < n)
    return XR_ERROR_SIZE_INSUFFICIENT;
  for (std::uint32_t i = 0; i < n; ++i)
    fill(out[i], i);
  return XR_SUCCESS;
}

XrResult copyString(const std::string& s, std::uint32_t capacity, std::uint32_t* count, char* buffer) {
  return enumerate(capacity, count, buffer, std::uint32_t(s.size() + 1),
                   [&](char& c, std::uint32_t i) { c = i < s.size() ? s[i] : '\0'; });
}

// ---- the API ----
/// Runs `body` with the object of `handle` under the runtime's lock, or answers XR_ERROR_HANDLE_INVALID
/// (the specification's code for a handle that is not a live one of its type) without calling it.
template <class T, class H, class Body>
XrResult checked(H handle, Body&& body) {
  std::lock_guard<std::recursive_mutex> lock(g_mutex);
  T* object = lookup<T>(handleOf(handle), T::kKind);
  return object ? body(object) : XR_ERROR_HANDLE_INVALID;
}

#define LOCK std::lock_guard<std::recursive_mutex> lock(g_mutex)

struct ExtensionInfo {
  const char* name;
  std::uint32_t version;
  bool enabled;
};
std::vector<ExtensionInfo> offeredExtensions() {
  std::vector<ExtensionInfo> out;
  if (g_config->gl)
    out.push_back({XR_KHR_OPENGL_ENABLE_EXTENSION_NAME, XR_KHR_opengl_enable_SPEC_VERSION, true});
  if (g_config->handTracking)
    out.push_back({XR_EXT_HAND_TRACKING_EXTENSION_NAME, XR_EXT_hand_tracking_SPEC_VERSION, true});
  out.push_back(
      {XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME, XR_KHR_composition_layer_depth_SPEC_VERSION, true});
  return out;
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateInstanceExtensionProperties(const char* layerName, uint32_t capacity,
                                                                    uint32_t* count,
                                                                    XrExtensionProperties* props) {
  LOCK;
  if (layerName && *layerName)
    return XR_ERROR_API_LAYER_NOT_PRESENT;
  const auto ext = offeredExtensions();
  return enumerate(capacity, count, props, std::uint32_t(ext.size()),
                   [&](XrExtensionProperties& p, std::uint32_t i) {
                     std::snprintf(p.extensionName, sizeof(p.extensionName), "%s", ext[i].name);
                     p.extensionVersion = ext[i].version;
                   });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateInstance(const XrInstanceCreateInfo* info, XrInstance* instance) {
  LOCK;
  if (!info || info->type != XR_TYPE_INSTANCE_CREATE_INFO || !instance)
    return XR_ERROR_VALIDATION_FAILURE;
  if (XR_VERSION_MAJOR(info->applicationInfo.apiVersion) != 1)
    return XR_ERROR_API_VERSION_UNSUPPORTED;
  auto inst = std::make_unique<Instance>();
  const auto ext = offeredExtensions();
  for (std::uint32_t i = 0; i < info->enabledExtensionCount; ++i) {
    const std::string name = info->enabledExtensionNames[i];
    if (std::none_of(ext.begin(), ext.end(), [&](const ExtensionInfo& e) { return name == e.name; }))
      return XR_ERROR_EXTENSION_NOT_PRESENT;
    inst->glExt |= name == XR_KHR_OPENGL_ENABLE_EXTENSION_NAME;
    inst->handExt |= name == XR_EXT_HAND_TRACKING_EXTENSION_NAME;
    inst->depthExt |= name == XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME;
  }
  if (info->enabledApiLayerCount > 0)
    return XR_ERROR_API_LAYER_NOT_PRESENT;  // the loader strips the layers it handles
  if (!g_config->hands.empty() && g_joints.empty()) {
    const auto& o = g_config->handOffset;
    g_joints = loadJoints(g_config->hands, Vec{o[0], o[1], o[2]});
  }
  *instance = create<Instance, XrInstance>(std::move(inst), 0);
  return XR_SUCCESS;
}

void destroyTree(std::uint64_t handle) {
  std::vector<std::uint64_t> children;
  for (const auto& [h, o] : g_objects) {
    if (o->parent == handle)
      children.push_back(h);
  }
  for (std::uint64_t c : children)
    destroyTree(c);
  const auto it = g_objects.find(handle);
  if (it == g_objects.end())
    return;
  if (it->second->kind == Kind::Swapchain) {
    auto* sc = static_cast<Swapchain*>(it->second.get());
    if (!sc->textures.empty() && glXGetCurrentContext())
      g_gl.deleteTextures(GLsizei(sc->textures.size()), sc->textures.data());
  }
  g_objects.erase(it);
}

XRAPI_ATTR XrResult XRAPI_CALL DestroyInstance(XrInstance instance) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    destroyTree(handleOf(instance));
    ++g_stats.instancesDestroyed;
    writeStats();
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetInstanceProperties(XrInstance instance, XrInstanceProperties* props) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    props->runtimeVersion = XR_MAKE_VERSION(0, 1, 0);
    std::snprintf(props->runtimeName, sizeof(props->runtimeName), "FluidPlaying test runtime");
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL PollEvent(XrInstance instance, XrEventDataBuffer* event) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    if (inst->events.empty())
      return XR_EVENT_UNAVAILABLE;
    const XrEventDataBuffer e = inst->events.front();
    inst->events.pop_front();
    if (e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED) {
      const auto* sc = reinterpret_cast<const XrEventDataSessionStateChanged*>(&e);
      if (Session* s = lookup<Session>(handleOf(sc->session), Kind::Session))
        s->state = sc->state;
      else
        return PollEvent(instance, event);  // the session is gone: its events go with it
    }
    std::memcpy(event, &e, sizeof(e));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL ResultToString(XrInstance instance, XrResult value,
                                              char buffer[XR_MAX_RESULT_STRING_SIZE]) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "XR_RESULT_%d", int(value));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL StructureTypeToString(XrInstance instance, XrStructureType value,
                                                     char buffer[XR_MAX_STRUCTURE_NAME_SIZE]) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "XR_STRUCTURE_TYPE_%d", int(value));
    return XR_SUCCESS;
  });
}

constexpr XrSystemId kSystem = 1;

XRAPI_ATTR XrResult XRAPI_CALL GetSystem(XrInstance instance, const XrSystemGetInfo* info,
                                         XrSystemId* systemId) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY &&
        info->formFactor != XR_FORM_FACTOR_HANDHELD_DISPLAY)
      return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
    if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY || !g_config->hmd)
      return XR_ERROR_FORM_FACTOR_UNAVAILABLE;
    *systemId = kSystem;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetSystemProperties(XrInstance instance, XrSystemId systemId,
                                                   XrSystemProperties* props) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    if (systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    props->systemId = kSystem;
    props->vendorId = 0xf1u;
    std::snprintf(props->systemName, sizeof(props->systemName), "FluidPlaying test HMD");
    props->graphicsProperties = {2048, 2048, 16};
    props->trackingProperties = {XR_TRUE, XR_TRUE};
    for (auto* next = reinterpret_cast<XrBaseOutStructure*>(props->next); next; next = next->next) {
      if (next->type == XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT)
        reinterpret_cast<XrSystemHandTrackingPropertiesEXT*>(next)->supportsHandTracking =
            inst->handExt && g_config->handTracking ? XR_TRUE : XR_FALSE;
    }
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateEnvironmentBlendModes(XrInstance instance, XrSystemId systemId,
                                                              XrViewConfigurationType type, uint32_t capacity,
                                                              uint32_t* count,
                                                              XrEnvironmentBlendMode* modes) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    if (systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
      return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    return enumerate(capacity, count, modes, 1u,
                     [](XrEnvironmentBlendMode& m, std::uint32_t) { m = XR_ENVIRONMENT_BLEND_MODE_OPAQUE; });
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateViewConfigurations(XrInstance instance, XrSystemId systemId,
                                                           uint32_t capacity, uint32_t* count,
                                                           XrViewConfigurationType* types) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    if (systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    return enumerate(capacity, count, types, 1u, [](XrViewConfigurationType& t, std::uint32_t) {
      t = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
    });
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetViewConfigurationProperties(XrInstance instance, XrSystemId systemId,
                                                              XrViewConfigurationType type,
                                                              XrViewConfigurationProperties* props) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    if (systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
      return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    props->viewConfigurationType = type;
    props->fovMutable = XR_FALSE;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateViewConfigurationViews(XrInstance instance, XrSystemId systemId,
                                                               XrViewConfigurationType type,
                                                               uint32_t capacity, uint32_t* count,
                                                               XrViewConfigurationView* views) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    if (systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
      return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    const auto w = std::uint32_t(g_config->size[0]),
               h = std::uint32_t(g_config->size.size() > 1 ? g_config->size[1] : w);
    return enumerate(capacity, count, views, 2u, [&](XrViewConfigurationView& v, std::uint32_t) {
      v.recommendedImageRectWidth = w;
      v.recommendedImageRectHeight = h;
      v.maxImageRectWidth = 4096;
      v.maxImageRectHeight = 4096;
      v.recommendedSwapchainSampleCount = 1;
      v.maxSwapchainSampleCount = 1;
    });
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetOpenGLGraphicsRequirementsKHR(XrInstance instance, XrSystemId systemId,
                                                                XrGraphicsRequirementsOpenGLKHR* req) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    if (systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    req->minApiVersionSupported = XR_MAKE_VERSION(3, 3, 0);
    req->maxApiVersionSupported = XR_MAKE_VERSION(4, 6, 0);
    inst->requirementsQueried = true;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateSession(XrInstance instance, const XrSessionCreateInfo* info,
                                             XrSession* session) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    if (info->systemId != kSystem)
      return XR_ERROR_SYSTEM_INVALID;
    if (!inst->requirementsQueried)
      return XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
    const XrGraphicsBindingOpenGLXlibKHR* binding = nullptr;
    for (auto* next = reinterpret_cast<const XrBaseInStructure*>(info->next); next; next = next->next) {
      if (next->type == XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR)
        binding = reinterpret_cast<const XrGraphicsBindingOpenGLXlibKHR*>(next);
    }
    if (!binding || !binding->xDisplay || !binding->glxContext)
      return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    if (inst->session)
      return XR_ERROR_LIMIT_REACHED;
    if (glXGetCurrentContext() != binding->glxContext || !g_gl.load())
      return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    auto s = std::make_unique<Session>();
    const XrSession h = create<Session, XrSession>(std::move(s), handleOf(instance));
    inst->session = handleOf(h);
    queueState(*inst, handleOf(h), XR_SESSION_STATE_IDLE);
    queueState(*inst, handleOf(h), XR_SESSION_STATE_READY);
    ++g_stats.sessions;
    *session = h;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL DestroySession(XrSession session) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    Instance* inst = instanceOf(handleOf(session));
    inst->session = 0;
    destroyTree(handleOf(session));
    writeStats();
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL BeginSession(XrSession session, const XrSessionBeginInfo* info) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (info->primaryViewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
      return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    if (s->running)
      return XR_ERROR_SESSION_RUNNING;
    if (s->state != XR_SESSION_STATE_READY)
      return XR_ERROR_SESSION_NOT_READY;
    s->running = true;
    s->beginTime = runtimeNow();
    s->lastDisplay = s->beginTime;
    ++g_stats.begun;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EndSession(XrSession session) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (!s->running)
      return XR_ERROR_SESSION_NOT_RUNNING;
    if (s->state != XR_SESSION_STATE_STOPPING)
      return XR_ERROR_SESSION_NOT_STOPPING;
    s->running = false;
    s->waited = s->begun = false;
    Instance* inst = instanceOf(handleOf(session));
    queueState(*inst, handleOf(session), XR_SESSION_STATE_IDLE);
    // an exit the application asked for, or one the runtime scripted: the session ends for good
    queueState(*inst, handleOf(session), XR_SESSION_STATE_EXITING);
    ++g_stats.ended;
    writeStats();
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL RequestExitSession(XrSession session) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (!s->running)
      return XR_ERROR_SESSION_NOT_RUNNING;
    s->exitRequested = true;
    queueStop(*instanceOf(handleOf(session)), handleOf(session), *s);
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL WaitFrame(XrSession session, const XrFrameWaitInfo* info,
                                         XrFrameState* state) {
  std::int64_t sleepUntil = 0;
  {
    LOCK;
    (void)info;
    Session* s = lookup<Session>(handleOf(session), Kind::Session);
    if (!s)
      return XR_ERROR_HANDLE_INVALID;
    if (!s->running)
      return XR_ERROR_SESSION_NOT_RUNNING;
    s->waitCalled = runtimeNow();
    const std::int64_t period = g_config->period;
    XrTime display = s->lastDisplay + period;
    if (!g_config->virtualTime) {
      // the frame must start at least half a period before its display time: a late one takes a later slot
      const XrTime now = runtimeNow();
      while (display - period / 2 < now) {
        display += period;
        ++g_stats.missed;
      }
      sleepUntil = display - period + g_startNs - 1000000000LL;
    }
    s->lastDisplay = display;
    s->waitedDisplay = display;
    s->waited = true;
    ++s->frame;
    ++g_stats.waited;
    Instance* inst = instanceOf(handleOf(session));
    if (s->frame == 1) {
      queueState(*inst, handleOf(session), XR_SESSION_STATE_SYNCHRONIZED);
      queueState(*inst, handleOf(session), XR_SESSION_STATE_VISIBLE);
      queueState(*inst, handleOf(session), XR_SESSION_STATE_FOCUSED);
    }
    runEvents(*inst, handleOf(session), *s);
    state->predictedDisplayTime = display;
    state->predictedDisplayPeriod = period;
    state->shouldRender = s->state == XR_SESSION_STATE_VISIBLE || s->state == XR_SESSION_STATE_FOCUSED;
  }
  if (sleepUntil > 0) {
    const std::int64_t wait = sleepUntil - nowNs();
    if (wait > 0)
      std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
  }
  LOCK;
  if (Session* s = lookup<Session>(handleOf(session), Kind::Session))
    s->waitReturned = runtimeNow();
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL BeginFrame(XrSession session, const XrFrameBeginInfo*) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (!s->running)
      return XR_ERROR_SESSION_NOT_RUNNING;
    if (!s->waited)
      return XR_ERROR_CALL_ORDER_INVALID;
    s->waited = false;
    if (s->begun)
      return XR_FRAME_DISCARDED;  // the previous begun frame was never ended
    s->begun = true;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EndFrame(XrSession session, const XrFrameEndInfo* info) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (!s->running)
      return XR_ERROR_SESSION_NOT_RUNNING;
    if (!s->begun)
      return XR_ERROR_CALL_ORDER_INVALID;
    if (info->displayTime != s->waitedDisplay)
      return XR_ERROR_TIME_INVALID;
    if (info->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE)
      return XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED;
    if (info->layerCount > 16)
      return XR_ERROR_LAYER_LIMIT_EXCEEDED;
    // capture "FRAME,DIR"
    long captureFrame = -1;
    std::string captureDir;
    if (!g_config->capture.empty()) {
      const std::size_t comma = g_config->capture.find(',');
      captureFrame = std::atol(g_config->capture.substr(0, comma).c_str());
      captureDir = g_config->capture.substr(comma + 1);
    }
    for (std::uint32_t l = 0; l < info->layerCount; ++l) {
      const XrCompositionLayerBaseHeader* layer = info->layers[l];
      if (!layer)
        return XR_ERROR_LAYER_INVALID;
      if (layer->type != XR_TYPE_COMPOSITION_LAYER_PROJECTION)
        return XR_ERROR_LAYER_INVALID;
      const auto* proj = reinterpret_cast<const XrCompositionLayerProjection*>(layer);
      if (!lookup<Space>(handleOf(proj->space), Kind::Space))
        return XR_ERROR_HANDLE_INVALID;
      if (proj->viewCount != 2)
        return XR_ERROR_VALIDATION_FAILURE;
      for (std::uint32_t v = 0; v < 2; ++v) {
        const XrSwapchainSubImage& sub = proj->views[v].subImage;
        Swapchain* sc = lookup<Swapchain>(handleOf(sub.swapchain), Kind::Swapchain);
        if (!sc)
          return XR_ERROR_HANDLE_INVALID;
        if (sc->released < 0)
          return XR_ERROR_LAYER_INVALID;
        if (sub.imageRect.offset.x < 0 || sub.imageRect.offset.y < 0 || sub.imageRect.extent.width <= 0 ||
            sub.imageRect.extent.height <= 0 ||
            std::uint32_t(sub.imageRect.offset.x + sub.imageRect.extent.width) > sc->width ||
            std::uint32_t(sub.imageRect.offset.y + sub.imageRect.extent.height) > sc->height)
          return XR_ERROR_SWAPCHAIN_RECT_INVALID;
        if (!poseValid(proj->views[v].pose))
          return XR_ERROR_POSE_INVALID;
        if (captureFrame == g_stats.waited)
          captureImage(*sc, std::uint32_t(sc->released), sub.imageRect,
                       captureDir + "/eye" + std::to_string(v) + ".ppm");
        for (auto* next = reinterpret_cast<const XrBaseInStructure*>(proj->views[v].next); next;
             next = next->next) {
          if (next->type == XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR) {
            const auto* depth = reinterpret_cast<const XrCompositionLayerDepthInfoKHR*>(next);
            Swapchain* dsc = lookup<Swapchain>(handleOf(depth->subImage.swapchain), Kind::Swapchain);
            if (!dsc)
              return XR_ERROR_HANDLE_INVALID;
            if (dsc->released < 0)
              return XR_ERROR_LAYER_INVALID;
          }
        }
      }
    }
    s->begun = false;
    if (!g_config->frameLog.empty()) {
      std::ofstream log(g_config->frameLog, std::ios::app);
      log << s->waitedDisplay << ' ' << runtimeNow() << ' ' << s->waitCalled << ' ' << s->waitReturned;
      for (std::uint32_t v = 0; v < 2; ++v) {
        const auto* proj = info->layerCount
                               ? reinterpret_cast<const XrCompositionLayerProjection*>(info->layers[0])
                               : nullptr;
        const Swapchain* sc =
            proj ? lookup<Swapchain>(handleOf(proj->views[v].subImage.swapchain), Kind::Swapchain) : nullptr;
        log << ' ' << (sc ? sc->acquiredAt : 0) << ' ' << (sc ? sc->releasedAt : 0);
      }
      if (g_config->frameHash) {
        const auto* proj = info->layerCount
                               ? reinterpret_cast<const XrCompositionLayerProjection*>(info->layers[0])
                               : nullptr;
        const Swapchain* sc =
            proj ? lookup<Swapchain>(handleOf(proj->views[0].subImage.swapchain), Kind::Swapchain) : nullptr;
        log << ' '
            << (sc ? hashImage(*sc, std::uint32_t(sc->released), proj->views[0].subImage.imageRect) : 0);
      }
      log << '\n';
    }
    ++g_stats.submitted;
    g_stats.layers += info->layerCount;
    if (s->frame % 16 == 0)
      writeStats();
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL LocateViews(XrSession session, const XrViewLocateInfo* info,
                                           XrViewState* viewState, uint32_t capacity, uint32_t* count,
                                           XrView* views) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    Space* base = lookup<Space>(handleOf(info->space), Kind::Space);
    if (!base)
      return XR_ERROR_HANDLE_INVALID;
    if (info->viewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
      return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
    if (info->displayTime <= 0)
      return XR_ERROR_TIME_INVALID;
    Pose baseInStage;
    const bool located = spaceInStage(*s, *base, info->displayTime, baseInStage);
    viewState->viewStateFlags =
        located ? XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT |
                      XR_VIEW_STATE_ORIENTATION_TRACKED_BIT | XR_VIEW_STATE_POSITION_TRACKED_BIT
                : 0;
    const Pose head = headPose();
    return enumerate(capacity, count, views, 2u, [&](XrView& v, std::uint32_t i) {
      const double side = i == 0 ? -1.0 : 1.0;
      const Pose eye = head * Pose{Quat{}, Vec{side * 0.5 * g_config->ipd, 0, 0}};
      v.pose = toXr(baseInStage.inverse() * eye);
      // asymmetric: each eye sees more on its outer side
      v.fov.angleLeft = i == 0 ? -0.95f : -0.80f;
      v.fov.angleRight = i == 0 ? 0.80f : 0.95f;
      v.fov.angleUp = 0.85f;
      v.fov.angleDown = -0.90f;
    });
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateReferenceSpaces(XrSession session, uint32_t capacity, uint32_t* count,
                                                        XrReferenceSpaceType* spaces) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    std::vector<XrReferenceSpaceType> types = {XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL};
    if (g_config->stage)
      types.push_back(XR_REFERENCE_SPACE_TYPE_STAGE);
    return enumerate(capacity, count, spaces, std::uint32_t(types.size()),
                     [&](XrReferenceSpaceType& t, std::uint32_t i) { t = types[i]; });
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateReferenceSpace(XrSession session, const XrReferenceSpaceCreateInfo* info,
                                                    XrSpace* space) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    if (info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_VIEW &&
        info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_LOCAL &&
        (info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE || !g_config->stage))
      return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
    if (!poseValid(info->poseInReferenceSpace))
      return XR_ERROR_POSE_INVALID;
    auto sp = std::make_unique<Space>();
    sp->type = info->referenceSpaceType;
    sp->offset = fromXr(info->poseInReferenceSpace);
    *space = create<Space, XrSpace>(std::move(sp), handleOf(session));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetReferenceSpaceBoundsRect(XrSession session, XrReferenceSpaceType type,
                                                           XrExtent2Df* bounds) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    if (type == XR_REFERENCE_SPACE_TYPE_STAGE && g_config->stage) {
      *bounds = {3.0f, 3.0f};
      return XR_SUCCESS;
    }
    if (type != XR_REFERENCE_SPACE_TYPE_VIEW && type != XR_REFERENCE_SPACE_TYPE_LOCAL)
      return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
    *bounds = {0.0f, 0.0f};
    return XR_SPACE_BOUNDS_UNAVAILABLE;
  });
}

int handOfPath(const Instance& inst, XrPath path) {
  if (path == XR_NULL_PATH || path >= inst.paths.size())
    return -1;
  if (inst.paths[path] == "/user/hand/left")
    return 0;
  if (inst.paths[path] == "/user/hand/right")
    return 1;
  return -1;
}

XRAPI_ATTR XrResult XRAPI_CALL CreateActionSpace(XrSession session, const XrActionSpaceCreateInfo* info,
                                                 XrSpace* space) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    Action* a = lookup<Action>(handleOf(info->action), Kind::Action);
    if (!a)
      return XR_ERROR_HANDLE_INVALID;
    if (a->type != XR_ACTION_TYPE_POSE_INPUT)
      return XR_ERROR_ACTION_TYPE_MISMATCH;
    if (info->subactionPath != XR_NULL_PATH &&
        std::find(a->subactions.begin(), a->subactions.end(), info->subactionPath) == a->subactions.end())
      return XR_ERROR_PATH_UNSUPPORTED;
    if (!poseValid(info->poseInActionSpace))
      return XR_ERROR_POSE_INVALID;
    auto sp = std::make_unique<Space>();
    sp->action = handleOf(info->action);
    sp->hand = handOfPath(*instanceOf(handleOf(session)), info->subactionPath);
    sp->offset = fromXr(info->poseInActionSpace);
    *space = create<Space, XrSpace>(std::move(sp), handleOf(session));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL LocateSpace(XrSpace space, XrSpace baseSpace, XrTime time,
                                           XrSpaceLocation* location) {
  LOCK;
  Space* sp = lookup<Space>(handleOf(space), Kind::Space);
  Space* base = lookup<Space>(handleOf(baseSpace), Kind::Space);
  if (!sp || !base)
    return XR_ERROR_HANDLE_INVALID;
  if (time <= 0)
    return XR_ERROR_TIME_INVALID;
  Session* s = lookup<Session>(sp->parent, Kind::Session);
  Pose a, b;
  if (!spaceInStage(*s, *sp, time, a) || !spaceInStage(*s, *base, time, b)) {
    location->locationFlags = 0;
    return XR_SUCCESS;
  }
  location->pose = toXr(b.inverse() * a);
  location->locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
                            XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT |
                            XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL DestroySpace(XrSpace space) {
  return checked<Space>(space, [&](Space*) -> XrResult {
    destroyTree(handleOf(space));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateSwapchainFormats(XrSession session, uint32_t capacity,
                                                         uint32_t* count, int64_t* formats) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    const auto& f = g_config->formats;
    return enumerate(capacity, count, formats, std::uint32_t(f.size()),
                     [&](int64_t& out, std::uint32_t i) { out = std::int64_t(f[i]); });
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateSwapchain(XrSession session, const XrSwapchainCreateInfo* info,
                                               XrSwapchain* swapchain) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    const auto& f = g_config->formats;
    if (std::find(f.begin(), f.end(), double(info->format)) == f.end())
      return XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED;
    if (info->width == 0 || info->height == 0 || info->width > 4096 || info->height > 4096 ||
        info->arraySize != 1 || info->faceCount != 1 || info->mipCount != 1 || info->sampleCount != 1)
      return XR_ERROR_FEATURE_UNSUPPORTED;
    if (!glXGetCurrentContext() || !g_gl.load())
      return XR_ERROR_GRAPHICS_DEVICE_INVALID;
    auto sc = std::make_unique<Swapchain>();
    sc->format = info->format;
    sc->width = info->width;
    sc->height = info->height;
    sc->textures.resize(3);
    GLint bound = 0;
    g_gl.getIntegerv(GL_TEXTURE_BINDING_2D, &bound);
    g_gl.genTextures(3, sc->textures.data());
    for (GLuint t : sc->textures) {
      g_gl.bindTexture(GL_TEXTURE_2D, t);
      g_gl.texStorage2D(GL_TEXTURE_2D, 1, GLenum(info->format), GLsizei(info->width), GLsizei(info->height));
      if (!g_gl.isTexture(t))
        return XR_ERROR_RUNTIME_FAILURE;
    }
    g_gl.bindTexture(GL_TEXTURE_2D, GLuint(bound));
    const XrSwapchain h = create<Swapchain, XrSwapchain>(std::move(sc), handleOf(session));
    s->swapchains.push_back(handleOf(h));
    *swapchain = h;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL DestroySwapchain(XrSwapchain swapchain) {
  return checked<Swapchain>(swapchain, [&](Swapchain*) -> XrResult {
    destroyTree(handleOf(swapchain));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateSwapchainImages(XrSwapchain swapchain, uint32_t capacity,
                                                        uint32_t* count, XrSwapchainImageBaseHeader* images) {
  return checked<Swapchain>(swapchain, [&](Swapchain* sc) -> XrResult {
    if (!count)
      return XR_ERROR_VALIDATION_FAILURE;
    *count = std::uint32_t(sc->textures.size());
    if (capacity == 0)
      return XR_SUCCESS;
    if (capacity < sc->textures.size())
      return XR_ERROR_SIZE_INSUFFICIENT;
    if (images[0].type != XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR)
      return XR_ERROR_VALIDATION_FAILURE;
    auto* gl = reinterpret_cast<XrSwapchainImageOpenGLKHR*>(images);
    for (std::size_t i = 0; i < sc->textures.size(); ++i)
      gl[i].image = sc->textures[i];
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL AcquireSwapchainImage(XrSwapchain swapchain,
                                                     const XrSwapchainImageAcquireInfo*, uint32_t* index) {
  return checked<Swapchain>(swapchain, [&](Swapchain* sc) -> XrResult {
    if (sc->acquired.size() >= sc->textures.size() - 1)
      return XR_ERROR_CALL_ORDER_INVALID;
    *index = sc->next;
    sc->acquiredAt = runtimeNow();
    sc->acquired.push_back(sc->next);
    sc->next = (sc->next + 1) % std::uint32_t(sc->textures.size());
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL WaitSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageWaitInfo*) {
  return checked<Swapchain>(swapchain, [&](Swapchain* sc) -> XrResult {
    if (sc->acquired.empty() || sc->waited)
      return XR_ERROR_CALL_ORDER_INVALID;
    sc->waited = true;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL ReleaseSwapchainImage(XrSwapchain swapchain,
                                                     const XrSwapchainImageReleaseInfo*) {
  return checked<Swapchain>(swapchain, [&](Swapchain* sc) -> XrResult {
    if (sc->acquired.empty() || !sc->waited)
      return XR_ERROR_CALL_ORDER_INVALID;
    if (!g_config->frameLog.empty())
      g_gl.finish();  // the image complete, as a compositor waits for it: its drawing time is the eye's
    sc->released = int(sc->acquired.front());
    sc->releasedAt = runtimeNow();
    sc->acquired.pop_front();
    sc->waited = false;
    return XR_SUCCESS;
  });
}

// ---- paths and actions ----

bool pathWellFormed(const std::string& p) {
  if (p.empty() || p[0] != '/' || p.back() == '/')
    return false;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const char c = p[i];
    if (c == '/' && i + 1 < p.size() && p[i + 1] == '/')
      return false;
    if (!(std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) ||
          c == '/' || c == '-' || c == '_' || c == '.'))
      return false;
  }
  return true;
}

XRAPI_ATTR XrResult XRAPI_CALL StringToPath(XrInstance instance, const char* str, XrPath* path) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    const std::string p = str;
    if (!pathWellFormed(p))
      return XR_ERROR_PATH_FORMAT_INVALID;
    const auto it = std::find(inst->paths.begin(), inst->paths.end(), p);
    *path = XrPath(it - inst->paths.begin());
    if (it == inst->paths.end())
      inst->paths.push_back(p);
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL PathToString(XrInstance instance, XrPath path, uint32_t capacity,
                                            uint32_t* count, char* buffer) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    if (path == XR_NULL_PATH || path >= inst->paths.size())
      return XR_ERROR_PATH_INVALID;
    return copyString(inst->paths[path], capacity, count, buffer);
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateActionSet(XrInstance instance, const XrActionSetCreateInfo* info,
                                               XrActionSet* set) {
  return checked<Instance>(instance, [&](Instance*) -> XrResult {
    if (!pathWellFormed("/" + std::string(info->actionSetName)) ||
        std::string(info->actionSetName).find('/') != std::string::npos)
      return XR_ERROR_PATH_FORMAT_INVALID;
    for (const auto& [h, o] : g_objects) {
      if (o->kind == Kind::ActionSet && static_cast<ActionSet*>(o.get())->name == info->actionSetName)
        return XR_ERROR_NAME_DUPLICATED;
    }
    auto as = std::make_unique<ActionSet>();
    as->name = info->actionSetName;
    *set = create<ActionSet, XrActionSet>(std::move(as), handleOf(instance));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL DestroyActionSet(XrActionSet set) {
  return checked<ActionSet>(set, [&](ActionSet*) -> XrResult {
    destroyTree(handleOf(set));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateAction(XrActionSet set, const XrActionCreateInfo* info,
                                            XrAction* action) {
  return checked<ActionSet>(set, [&](ActionSet* as) -> XrResult {
    if (as->attached)
      return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    if (std::string(info->actionName).find('/') != std::string::npos ||
        !pathWellFormed("/" + std::string(info->actionName)))
      return XR_ERROR_PATH_FORMAT_INVALID;
    Instance* inst = instanceOf(handleOf(set));
    auto a = std::make_unique<Action>();
    a->type = info->actionType;
    a->name = info->actionName;
    for (std::uint32_t i = 0; i < info->countSubactionPaths; ++i) {
      if (handOfPath(*inst, info->subactionPaths[i]) < 0)
        return XR_ERROR_PATH_UNSUPPORTED;
      a->subactions.push_back(info->subactionPaths[i]);
    }
    *action = create<Action, XrAction>(std::move(a), handleOf(set));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL DestroyAction(XrAction action) {
  return checked<Action>(action, [&](Action*) -> XrResult {
    destroyTree(handleOf(action));
    return XR_SUCCESS;
  });
}

/// the input components of the profiles the runtime knows, per hand (without /user/hand/X)
const std::map<std::string, std::set<std::string>>& profiles() {
  static const std::map<std::string, std::set<std::string>> p = {
      {"/interaction_profiles/khr/simple_controller",
       {"/input/select/click", "/input/menu/click", "/input/grip/pose", "/input/aim/pose", "/output/haptic"}},
      {"/interaction_profiles/valve/index_controller",
       {"/input/trigger/value", "/input/trigger/click", "/input/squeeze/value", "/input/squeeze/force",
        "/input/system/click", "/input/a/click", "/input/b/click", "/input/grip/pose", "/input/aim/pose",
        "/output/haptic"}},
      {"/interaction_profiles/oculus/touch_controller",
       {"/input/trigger/value", "/input/squeeze/value", "/input/menu/click", "/input/x/click",
        "/input/a/click", "/input/grip/pose", "/input/aim/pose", "/output/haptic"}},
  };
  return p;
}

XRAPI_ATTR XrResult XRAPI_CALL
SuggestInteractionProfileBindings(XrInstance instance, const XrInteractionProfileSuggestedBinding* s) {
  return checked<Instance>(instance, [&](Instance* inst) -> XrResult {
    if (s->interactionProfile == XR_NULL_PATH || s->interactionProfile >= inst->paths.size())
      return XR_ERROR_PATH_INVALID;
    const std::string profile = inst->paths[s->interactionProfile];
    const auto it = profiles().find(profile);
    if (it == profiles().end())
      return XR_ERROR_PATH_UNSUPPORTED;
    std::map<std::uint64_t, std::vector<std::string>> bound;
    for (std::uint32_t i = 0; i < s->countSuggestedBindings; ++i) {
      const XrActionSuggestedBinding& b = s->suggestedBindings[i];
      Action* a = lookup<Action>(handleOf(b.action), Kind::Action);
      if (!a)
        return XR_ERROR_HANDLE_INVALID;
      if (lookup<ActionSet>(a->parent, Kind::ActionSet)->attached)
        return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
      if (b.binding == XR_NULL_PATH || b.binding >= inst->paths.size())
        return XR_ERROR_PATH_INVALID;
      const std::string path = inst->paths[b.binding];
      std::string component;
      for (const char* user : {"/user/hand/left", "/user/hand/right"}) {
        if (path.rfind(user, 0) == 0)
          component = path.substr(std::strlen(user));
      }
      if (component.empty() || !it->second.count(component))
        return XR_ERROR_PATH_UNSUPPORTED;
      bound[handleOf(b.action)].push_back(path);
    }
    for (auto& [h, paths] : bound)
      lookup<Action>(h, Kind::Action)->bindings[profile] = paths;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL AttachSessionActionSets(XrSession session,
                                                       const XrSessionActionSetsAttachInfo* info) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (s->attached)
      return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    for (std::uint32_t i = 0; i < info->countActionSets; ++i) {
      ActionSet* as = lookup<ActionSet>(handleOf(info->actionSets[i]), Kind::ActionSet);
      if (!as)
        return XR_ERROR_HANDLE_INVALID;
    }
    for (std::uint32_t i = 0; i < info->countActionSets; ++i) {
      lookup<ActionSet>(handleOf(info->actionSets[i]), Kind::ActionSet)->attached = true;
      s->actionSets.insert(handleOf(info->actionSets[i]));
    }
    s->attached = true;
    // the controllers are there from the start: the interaction profile is current at once
    Instance* inst = instanceOf(handleOf(session));
    XrEventDataBuffer buffer{};
    auto* e = reinterpret_cast<XrEventDataInteractionProfileChanged*>(&buffer);
    e->type = XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED;
    e->session = session;
    inst->events.push_back(buffer);
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetCurrentInteractionProfile(XrSession session, XrPath topLevelUserPath,
                                                            XrInteractionProfileState* state) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    if (!s->attached)
      return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    Instance* inst = instanceOf(handleOf(session));
    if (handOfPath(*inst, topLevelUserPath) < 0)
      return XR_ERROR_PATH_UNSUPPORTED;
    XrPath p = XR_NULL_PATH;
    StringToPath(reinterpret_cast<XrInstance>(std::uintptr_t(s->parent)), g_config->profile.c_str(), &p);
    state->interactionProfile = p;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL SyncActions(XrSession session, const XrActionsSyncInfo* info) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    for (std::uint32_t i = 0; i < info->countActiveActionSets; ++i) {
      const std::uint64_t h = handleOf(info->activeActionSets[i].actionSet);
      if (!lookup<ActionSet>(h, Kind::ActionSet))
        return XR_ERROR_HANDLE_INVALID;
      if (!s->actionSets.count(h))
        return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    }
    if (s->state != XR_SESSION_STATE_FOCUSED)
      return XR_SESSION_NOT_FOCUSED;
    return XR_SUCCESS;
  });
}

/// the value of `component` ("/input/trigger/value") of controller `hand`, and whether it is active
bool componentValue(const Session& s, int hand, const std::string& component, float& value) {
  if (s.lost[hand] || s.state != XR_SESSION_STATE_FOCUSED)
    return false;
  const double trigger = g_config->controllers[0],
               squeeze = g_config->controllers.size() > 1 ? g_config->controllers[1] : 0.0;
  if (component == "/input/trigger/value")
    value = float(trigger);
  else if (component == "/input/trigger/click" || component == "/input/select/click")
    value = trigger > 0.5 ? 1.0f : 0.0f;
  else if (component == "/input/squeeze/value" || component == "/input/squeeze/force")
    value = float(squeeze);
  else if (component == "/input/menu/click")
    value = s.menu ? 1.0f : 0.0f;
  else
    value = 0.0f;
  return true;
}

/// the action's state over its bindings of the current profile, for the hand of `subaction` (or both)
XrResult actionValue(XrSession session, const XrActionStateGetInfo* info, XrActionType type, float& value,
                     bool& active) {
  Session* s = lookup<Session>(handleOf(session), Kind::Session);
  if (!s)
    return XR_ERROR_HANDLE_INVALID;
  Action* a = lookup<Action>(handleOf(info->action), Kind::Action);
  if (!a)
    return XR_ERROR_HANDLE_INVALID;
  if (a->type != type)
    return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (!s->actionSets.count(a->parent))
    return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  Instance* inst = instanceOf(handleOf(session));
  int onlyHand = -1;
  if (info->subactionPath != XR_NULL_PATH) {
    if (std::find(a->subactions.begin(), a->subactions.end(), info->subactionPath) == a->subactions.end())
      return XR_ERROR_PATH_UNSUPPORTED;
    onlyHand = handOfPath(*inst, info->subactionPath);
  }
  value = 0.0f;
  active = false;
  const auto it = a->bindings.find(g_config->profile);
  if (it == a->bindings.end())
    return XR_SUCCESS;
  for (const std::string& path : it->second) {
    const int hand = path.rfind("/user/hand/left", 0) == 0 ? 0 : 1;
    if (onlyHand >= 0 && hand != onlyHand)
      continue;
    float v = 0.0f;
    if (componentValue(*s, hand, path.substr(path.find("/input")), v)) {
      active = true;
      value = std::max(value, v);
    }
  }
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL GetActionStateBoolean(XrSession session, const XrActionStateGetInfo* info,
                                                     XrActionStateBoolean* state) {
  LOCK;
  float v = 0;
  bool active = false;
  const XrResult r = actionValue(session, info, XR_ACTION_TYPE_BOOLEAN_INPUT, v, active);
  if (r != XR_SUCCESS)
    return r;
  state->currentState = v > 0.5f ? XR_TRUE : XR_FALSE;
  state->changedSinceLastSync = XR_FALSE;
  state->lastChangeTime = 0;
  state->isActive = active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL GetActionStateFloat(XrSession session, const XrActionStateGetInfo* info,
                                                   XrActionStateFloat* state) {
  LOCK;
  float v = 0;
  bool active = false;
  const XrResult r = actionValue(session, info, XR_ACTION_TYPE_FLOAT_INPUT, v, active);
  if (r != XR_SUCCESS)
    return r;
  state->currentState = v;
  state->changedSinceLastSync = XR_FALSE;
  state->lastChangeTime = 0;
  state->isActive = active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL GetActionStatePose(XrSession session, const XrActionStateGetInfo* info,
                                                  XrActionStatePose* state) {
  return checked<Session>(session, [&](Session* s) -> XrResult {
    Action* a = lookup<Action>(handleOf(info->action), Kind::Action);
    if (!a)
      return XR_ERROR_HANDLE_INVALID;
    if (a->type != XR_ACTION_TYPE_POSE_INPUT)
      return XR_ERROR_ACTION_TYPE_MISMATCH;
    if (!s->actionSets.count(a->parent))
      return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    int hand = -1;
    if (info->subactionPath != XR_NULL_PATH) {
      if (std::find(a->subactions.begin(), a->subactions.end(), info->subactionPath) == a->subactions.end())
        return XR_ERROR_PATH_UNSUPPORTED;
      hand = handOfPath(*instanceOf(handleOf(session)), info->subactionPath);
    }
    const auto it = a->bindings.find(g_config->profile);
    bool active = false;
    if (it != a->bindings.end() && s->state == XR_SESSION_STATE_FOCUSED) {
      for (const std::string& path : it->second) {
        const int h = path.rfind("/user/hand/left", 0) == 0 ? 0 : 1;
        active |= (hand < 0 || h == hand) && !s->lost[h];
      }
    }
    state->isActive = active ? XR_TRUE : XR_FALSE;
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetActionStateVector2f(XrSession session, const XrActionStateGetInfo* info,
                                                      XrActionStateVector2f* state) {
  LOCK;
  float v = 0;
  bool active = false;
  const XrResult r = actionValue(session, info, XR_ACTION_TYPE_VECTOR2F_INPUT, v, active);
  if (r != XR_SUCCESS)
    return r;
  state->currentState = {0.0f, 0.0f};
  state->isActive = XR_FALSE;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL ApplyHapticFeedback(XrSession session, const XrHapticActionInfo* info,
                                                   const XrHapticBaseHeader*) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    Action* a = lookup<Action>(handleOf(info->action), Kind::Action);
    if (!a)
      return XR_ERROR_HANDLE_INVALID;
    return a->type == XR_ACTION_TYPE_VIBRATION_OUTPUT ? XR_SUCCESS : XR_ERROR_ACTION_TYPE_MISMATCH;
  });
}

// ---- hand tracking ----

XRAPI_ATTR XrResult XRAPI_CALL CreateHandTrackerEXT(XrSession session, const XrHandTrackerCreateInfoEXT* info,
                                                    XrHandTrackerEXT* tracker) {
  return checked<Session>(session, [&](Session*) -> XrResult {
    Instance* inst = instanceOf(handleOf(session));
    if (!inst->handExt)
      return XR_ERROR_FUNCTION_UNSUPPORTED;
    if (!g_config->handTracking)
      return XR_ERROR_FEATURE_UNSUPPORTED;
    if (info->hand != XR_HAND_LEFT_EXT && info->hand != XR_HAND_RIGHT_EXT)
      return XR_ERROR_VALIDATION_FAILURE;
    if (info->handJointSet != XR_HAND_JOINT_SET_DEFAULT_EXT)
      return XR_ERROR_VALIDATION_FAILURE;
    auto t = std::make_unique<HandTracker>();
    t->hand = info->hand == XR_HAND_LEFT_EXT ? 0 : 1;
    *tracker = create<HandTracker, XrHandTrackerEXT>(std::move(t), handleOf(session));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL DestroyHandTrackerEXT(XrHandTrackerEXT tracker) {
  return checked<HandTracker>(tracker, [&](HandTracker*) -> XrResult {
    destroyTree(handleOf(tracker));
    return XR_SUCCESS;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL LocateHandJointsEXT(XrHandTrackerEXT tracker,
                                                   const XrHandJointsLocateInfoEXT* info,
                                                   XrHandJointLocationsEXT* locations) {
  return checked<HandTracker>(tracker, [&](HandTracker* t) -> XrResult {
    Space* base = lookup<Space>(handleOf(info->baseSpace), Kind::Space);
    if (!base)
      return XR_ERROR_HANDLE_INVALID;
    if (info->time <= 0)
      return XR_ERROR_TIME_INVALID;
    if (locations->jointCount != XR_HAND_JOINT_COUNT_EXT)
      return XR_ERROR_VALIDATION_FAILURE;
    Session* s = lookup<Session>(t->parent, Kind::Session);
    XrHandJointVelocitiesEXT* velocities = nullptr;
    for (auto* next = reinterpret_cast<XrBaseOutStructure*>(locations->next); next; next = next->next) {
      if (next->type == XR_TYPE_HAND_JOINT_VELOCITIES_EXT)
        velocities = reinterpret_cast<XrHandJointVelocitiesEXT*>(next);
    }
    Pose baseInStage;
    const JointSample j = sampleJoints(g_joints, t->hand, sessionSeconds(*s, info->time));
    const bool active = j.valid && !s->lost[t->hand] && spaceInStage(*s, *base, info->time, baseInStage) &&
                        s->state == XR_SESSION_STATE_FOCUSED;
    locations->isActive = active ? XR_TRUE : XR_FALSE;
    for (std::uint32_t k = 0; k < XR_HAND_JOINT_COUNT_EXT; ++k) {
      XrHandJointLocationEXT& loc = locations->jointLocations[k];
      if (!active) {
        loc.locationFlags = 0;
        continue;
      }
      loc.pose = toXr(baseInStage.inverse() * j.pose[k]);
      loc.radius = float(j.radius[k]);
      loc.locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
                          XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
      if (velocities && velocities->jointCount == XR_HAND_JOINT_COUNT_EXT)
        velocities->jointVelocities[k].velocityFlags = 0;  // no velocities: the app differentiates the poses
    }
    return XR_SUCCESS;
  });
}

// ---- dispatch ----

XRAPI_ATTR XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance instance, const char* name,
                                                   PFN_xrVoidFunction* function);

struct Entry {
  const char* name;
  PFN_xrVoidFunction fn;
  int needs;  // 0 core, 1 XR_KHR_opengl_enable, 2 XR_EXT_hand_tracking
};
#define FP_ENTRY(n, needs) \
  { "xr" #n, reinterpret_cast<PFN_xrVoidFunction>(&n), needs }
const Entry kEntries[] = {
    FP_ENTRY(GetInstanceProcAddr, 0),
    FP_ENTRY(EnumerateInstanceExtensionProperties, 0),
    FP_ENTRY(CreateInstance, 0),
    FP_ENTRY(DestroyInstance, 0),
    FP_ENTRY(GetInstanceProperties, 0),
    FP_ENTRY(PollEvent, 0),
    FP_ENTRY(ResultToString, 0),
    FP_ENTRY(StructureTypeToString, 0),
    FP_ENTRY(GetSystem, 0),
    FP_ENTRY(GetSystemProperties, 0),
    FP_ENTRY(EnumerateEnvironmentBlendModes, 0),
    FP_ENTRY(CreateSession, 0),
    FP_ENTRY(DestroySession, 0),
    FP_ENTRY(EnumerateReferenceSpaces, 0),
    FP_ENTRY(CreateReferenceSpace, 0),
    FP_ENTRY(GetReferenceSpaceBoundsRect, 0),
    FP_ENTRY(CreateActionSpace, 0),
    FP_ENTRY(LocateSpace, 0),
    FP_ENTRY(DestroySpace, 0),
    FP_ENTRY(EnumerateViewConfigurations, 0),
    FP_ENTRY(GetViewConfigurationProperties, 0),
    FP_ENTRY(EnumerateViewConfigurationViews, 0),
    FP_ENTRY(EnumerateSwapchainFormats, 0),
    FP_ENTRY(CreateSwapchain, 0),
    FP_ENTRY(DestroySwapchain, 0),
    FP_ENTRY(EnumerateSwapchainImages, 0),
    FP_ENTRY(AcquireSwapchainImage, 0),
    FP_ENTRY(WaitSwapchainImage, 0),
    FP_ENTRY(ReleaseSwapchainImage, 0),
    FP_ENTRY(BeginSession, 0),
    FP_ENTRY(EndSession, 0),
    FP_ENTRY(RequestExitSession, 0),
    FP_ENTRY(WaitFrame, 0),
    FP_ENTRY(BeginFrame, 0),
    FP_ENTRY(EndFrame, 0),
    FP_ENTRY(LocateViews, 0),
    FP_ENTRY(StringToPath, 0),
    FP_ENTRY(PathToString, 0),
    FP_ENTRY(CreateActionSet, 0),
    FP_ENTRY(DestroyActionSet, 0),
    FP_ENTRY(CreateAction, 0),
    FP_ENTRY(DestroyAction, 0),
    FP_ENTRY(SuggestInteractionProfileBindings, 0),
    FP_ENTRY(AttachSessionActionSets, 0),
    FP_ENTRY(GetCurrentInteractionProfile, 0),
    FP_ENTRY(GetActionStateBoolean, 0),
    FP_ENTRY(GetActionStateFloat, 0),
    FP_ENTRY(GetActionStateVector2f, 0),
    FP_ENTRY(GetActionStatePose, 0),
    FP_ENTRY(SyncActions, 0),
    FP_ENTRY(ApplyHapticFeedback, 0),
    FP_ENTRY(GetOpenGLGraphicsRequirementsKHR, 1),
    FP_ENTRY(CreateHandTrackerEXT, 2),
    FP_ENTRY(DestroyHandTrackerEXT, 2),
    FP_ENTRY(LocateHandJointsEXT, 2),
};
#undef FP_ENTRY

XRAPI_ATTR XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance instance, const char* name,
                                                   PFN_xrVoidFunction* function) {
  LOCK;
  if (!name || !function)
    return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
  const std::string n = name;
  Instance* inst = lookup<Instance>(handleOf(instance), Kind::Instance);
  if (!inst) {
    if (instance != XR_NULL_HANDLE)
      return XR_ERROR_HANDLE_INVALID;
    // before an instance exists only these may be asked for
    if (n != "xrEnumerateInstanceExtensionProperties" && n != "xrCreateInstance" &&
        n != "xrGetInstanceProcAddr")
      return XR_ERROR_HANDLE_INVALID;
  }
  for (const Entry& e : kEntries) {
    if (n == e.name) {
      if (inst && ((e.needs == 1 && !inst->glExt) || (e.needs == 2 && !inst->handExt)))
        return XR_ERROR_FUNCTION_UNSUPPORTED;
      *function = e.fn;
      return XR_SUCCESS;
    }
  }
  return XR_ERROR_FUNCTION_UNSUPPORTED;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(
    const XrNegotiateLoaderInfo* loaderInfo, XrNegotiateRuntimeRequest* request) {
  if (!loaderInfo || !request || loaderInfo->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
      loaderInfo->structVersion != 1 || loaderInfo->structSize != sizeof(XrNegotiateLoaderInfo) ||
      request->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST || request->structVersion != 1 ||
      request->structSize != sizeof(XrNegotiateRuntimeRequest) || loaderInfo->minInterfaceVersion > 1 ||
      loaderInfo->maxInterfaceVersion < 1 || loaderInfo->minApiVersion > XR_CURRENT_API_VERSION ||
      loaderInfo->maxApiVersion < XR_MAKE_VERSION(1, 0, 0))
    return XR_ERROR_INITIALIZATION_FAILED;
  {
    LOCK;
    delete g_config;
    g_config = new Config();  // each negotiation reads the environment afresh (a test sets it per case)
    g_joints.clear();
    g_stats = Stats{};
    if (g_startNs == 0)
      g_startNs = nowNs();
  }
  request->runtimeInterfaceVersion = 1;
  request->runtimeApiVersion = XR_CURRENT_API_VERSION;
  request->getInstanceProcAddr = &GetInstanceProcAddr;
  return XR_SUCCESS;
}
