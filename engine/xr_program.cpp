#include "engine/xr_program.h"

// GLEW first, then GLX and X11 (whose macros Eigen must not see: Eigen is already in via xr_program.h)
#include "render/gl_api.h"

#include <GL/glx.h>
#include <X11/Xlib.h>

#define XR_USE_GRAPHICS_API_OPENGL
#define XR_USE_PLATFORM_XLIB
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <algorithm>
#include <cstring>
#include <vector>

namespace fp::engine {

namespace {

std::string resultName(XrInstance instance, XrResult r) {
  char buffer[XR_MAX_RESULT_STRING_SIZE] = {};
  if (instance != XR_NULL_HANDLE && xrResultToString(instance, r, buffer) == XR_SUCCESS)
    return buffer;
  return std::to_string(int(r));
}

void check(XrInstance instance, XrResult r, const char* what) {
  if (XR_FAILED(r))
    throw XrUnavailable(std::string(what) + " failed (" + resultName(instance, r) + ")");
}

sim::Quatd toQuat(const XrQuaternionf& q) {
  return sim::Quatd(q.w, q.x, q.y, q.z).normalized();
}
sim::Vec3d toVec(const XrVector3f& v) {
  return sim::Vec3d(v.x, v.y, v.z);
}

constexpr XrPosef kIdentity = {{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};

struct Eye {
  XrSwapchain color = XR_NULL_HANDLE;
  XrSwapchain depth = XR_NULL_HANDLE;
  std::vector<XrSwapchainImageOpenGLKHR> colorImages;
  std::vector<XrSwapchainImageOpenGLKHR> depthImages;
  int width = 0;
  int height = 0;
  GLuint framebuffer = 0;
  GLuint depthBuffer = 0;  // a renderbuffer where there is no depth swapchain
  std::uint32_t colorIndex = 0;
  std::uint32_t depthIndex = 0;
};

}  // namespace

struct XrProgram::Impl {
  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  bool handExt = false;
  bool depthExt = false;
  std::array<XrViewConfigurationView, 2> configs{};
  XrGraphicsRequirementsOpenGLKHR requirements{XR_TYPE_GRAPHICS_REQUIREMENTS_OPENGL_KHR};

  XrSession session = XR_NULL_HANDLE;
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;
  bool running = false;
  XrSpace space = XR_NULL_HANDLE;
  XrSpace view = XR_NULL_HANDLE;
  bool stage = false;
  std::array<Eye, 2> eyes;
  XrFrameState frame{XR_TYPE_FRAME_STATE};
  std::array<XrView, 2> views{{{XR_TYPE_VIEW}, {XR_TYPE_VIEW}}};

  XrActionSet actionSet = XR_NULL_HANDLE;
  XrAction gripAction = XR_NULL_HANDLE, triggerAction = XR_NULL_HANDLE, squeezeAction = XR_NULL_HANDLE,
           menuAction = XR_NULL_HANDLE;
  std::array<XrPath, 2> handPaths{};
  std::array<XrSpace, 2> gripSpaces{};
  std::array<XrHandTrackerEXT, 2> trackers{};
  bool menuWasDown = false;
  PFN_xrCreateHandTrackerEXT createHandTracker = nullptr;
  PFN_xrDestroyHandTrackerEXT destroyHandTracker = nullptr;
  PFN_xrLocateHandJointsEXT locateHandJoints = nullptr;

  XrPath path(const char* s) {
    XrPath p = XR_NULL_PATH;
    check(instance, xrStringToPath(instance, s, &p), "xrStringToPath");
    return p;
  }

  void destroySession() {
    for (XrHandTrackerEXT& t : trackers) {
      if (t != XR_NULL_HANDLE)
        destroyHandTracker(t);
      t = XR_NULL_HANDLE;
    }
    for (XrSpace& s : gripSpaces) {
      if (s != XR_NULL_HANDLE)
        xrDestroySpace(s);
      s = XR_NULL_HANDLE;
    }
    for (Eye& e : eyes) {
      if (e.framebuffer)
        glDeleteFramebuffers(1, &e.framebuffer);
      if (e.depthBuffer)
        glDeleteRenderbuffers(1, &e.depthBuffer);
      if (e.color != XR_NULL_HANDLE)
        xrDestroySwapchain(e.color);
      if (e.depth != XR_NULL_HANDLE)
        xrDestroySwapchain(e.depth);
      e = Eye{};
    }
    if (view != XR_NULL_HANDLE)
      xrDestroySpace(view);
    if (space != XR_NULL_HANDLE)
      xrDestroySpace(space);
    view = space = XR_NULL_HANDLE;
    if (actionSet != XR_NULL_HANDLE)
      xrDestroyActionSet(actionSet);  // its actions go with it
    actionSet = XR_NULL_HANDLE;
    if (session != XR_NULL_HANDLE)
      xrDestroySession(session);
    session = XR_NULL_HANDLE;
    state = XR_SESSION_STATE_UNKNOWN;
    running = false;
  }

  void createActions() {
    XrActionSetCreateInfo setInfo{XR_TYPE_ACTION_SET_CREATE_INFO};
    std::strcpy(setInfo.actionSetName, "hands");
    std::strcpy(setInfo.localizedActionSetName, "Hands");
    check(instance, xrCreateActionSet(instance, &setInfo, &actionSet), "xrCreateActionSet");
    handPaths = {path("/user/hand/left"), path("/user/hand/right")};
    auto action = [&](const char* name, XrActionType type) {
      XrActionCreateInfo info{XR_TYPE_ACTION_CREATE_INFO};
      std::strcpy(info.actionName, name);
      std::strcpy(info.localizedActionName, name);
      info.actionType = type;
      info.countSubactionPaths = 2;
      info.subactionPaths = handPaths.data();
      XrAction a = XR_NULL_HANDLE;
      check(instance, xrCreateAction(actionSet, &info, &a), "xrCreateAction");
      return a;
    };
    gripAction = action("grip", XR_ACTION_TYPE_POSE_INPUT);
    triggerAction = action("trigger", XR_ACTION_TYPE_FLOAT_INPUT);
    squeezeAction = action("squeeze", XR_ACTION_TYPE_FLOAT_INPUT);
    menuAction = action("recentre", XR_ACTION_TYPE_BOOLEAN_INPUT);
    auto suggest = [&](const char* profile, const std::vector<std::pair<XrAction, const char*>>& components) {
      std::vector<XrActionSuggestedBinding> bindings;
      for (const char* hand : {"/user/hand/left", "/user/hand/right"}) {
        for (const auto& [a, component] : components)
          bindings.push_back({a, path((std::string(hand) + component).c_str())});
      }
      XrInteractionProfileSuggestedBinding s{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
      s.interactionProfile = path(profile);
      s.countSuggestedBindings = std::uint32_t(bindings.size());
      s.suggestedBindings = bindings.data();
      check(instance, xrSuggestInteractionProfileBindings(instance, &s), profile);
    };
    suggest("/interaction_profiles/khr/simple_controller", {{gripAction, "/input/grip/pose"},
                                                            {triggerAction, "/input/select/click"},
                                                            {menuAction, "/input/menu/click"}});
    suggest("/interaction_profiles/valve/index_controller", {{gripAction, "/input/grip/pose"},
                                                             {triggerAction, "/input/trigger/value"},
                                                             {squeezeAction, "/input/squeeze/value"},
                                                             {menuAction, "/input/b/click"}});
    // the Touch's menu button is on the left controller only
    std::vector<XrActionSuggestedBinding> touch;
    for (const char* hand : {"/user/hand/left", "/user/hand/right"}) {
      touch.push_back({gripAction, path((std::string(hand) + "/input/grip/pose").c_str())});
      touch.push_back({triggerAction, path((std::string(hand) + "/input/trigger/value").c_str())});
      touch.push_back({squeezeAction, path((std::string(hand) + "/input/squeeze/value").c_str())});
    }
    touch.push_back({menuAction, path("/user/hand/left/input/menu/click")});
    XrInteractionProfileSuggestedBinding s{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
    s.interactionProfile = path("/interaction_profiles/oculus/touch_controller");
    s.countSuggestedBindings = std::uint32_t(touch.size());
    s.suggestedBindings = touch.data();
    check(instance, xrSuggestInteractionProfileBindings(instance, &s), "oculus/touch_controller bindings");
    XrSessionActionSetsAttachInfo attach{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
    attach.countActionSets = 1;
    attach.actionSets = &actionSet;
    check(instance, xrAttachSessionActionSets(session, &attach), "xrAttachSessionActionSets");
    for (int h = 0; h < 2; ++h) {
      XrActionSpaceCreateInfo info{XR_TYPE_ACTION_SPACE_CREATE_INFO};
      info.action = gripAction;
      info.subactionPath = handPaths[h];
      info.poseInActionSpace = kIdentity;
      check(instance, xrCreateActionSpace(session, &info, &gripSpaces[h]), "xrCreateActionSpace");
    }
  }

  void createSwapchains() {
    std::uint32_t count = 0;
    check(instance, xrEnumerateSwapchainFormats(session, 0, &count, nullptr), "xrEnumerateSwapchainFormats");
    std::vector<std::int64_t> formats(count);
    check(instance, xrEnumerateSwapchainFormats(session, count, &count, formats.data()),
          "xrEnumerateSwapchainFormats");
    auto pick = [&](std::initializer_list<std::int64_t> wanted) -> std::int64_t {
      for (std::int64_t w : wanted) {  // in our order of preference, sRGB first
        if (std::find(formats.begin(), formats.end(), w) != formats.end())
          return w;
      }
      return 0;
    };
    const std::int64_t color = pick({GL_SRGB8_ALPHA8, GL_RGBA8, GL_RGB10_A2, GL_RGBA16F});
    if (!color)
      throw XrUnavailable("the runtime offers no colour swapchain format this renderer can draw into");
    const std::int64_t depth =
        depthExt ? pick({GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT32F, GL_DEPTH24_STENCIL8}) : 0;
    for (int i = 0; i < 2; ++i) {
      Eye& e = eyes[i];
      e.width = int(configs[i].recommendedImageRectWidth);
      e.height = int(configs[i].recommendedImageRectHeight);
      auto make = [&](std::int64_t format, XrSwapchainUsageFlags usage,
                      std::vector<XrSwapchainImageOpenGLKHR>& images) {
        XrSwapchainCreateInfo info{XR_TYPE_SWAPCHAIN_CREATE_INFO};
        info.usageFlags = usage;
        info.format = format;
        info.sampleCount = 1;
        info.width = std::uint32_t(e.width);
        info.height = std::uint32_t(e.height);
        info.faceCount = 1;
        info.arraySize = 1;
        info.mipCount = 1;
        XrSwapchain sc = XR_NULL_HANDLE;
        check(instance, xrCreateSwapchain(session, &info, &sc), "xrCreateSwapchain");
        std::uint32_t n = 0;
        check(instance, xrEnumerateSwapchainImages(sc, 0, &n, nullptr), "xrEnumerateSwapchainImages");
        images.assign(n, {XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR});
        check(instance,
              xrEnumerateSwapchainImages(sc, n, &n,
                                         reinterpret_cast<XrSwapchainImageBaseHeader*>(images.data())),
              "xrEnumerateSwapchainImages");
        return sc;
      };
      e.color = make(color, XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT, e.colorImages);
      if (depth)
        e.depth = make(depth, XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, e.depthImages);
      glGenFramebuffers(1, &e.framebuffer);
      if (!depth) {
        glGenRenderbuffers(1, &e.depthBuffer);
        glBindRenderbuffer(GL_RENDERBUFFER, e.depthBuffer);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, e.width, e.height);
        glBindRenderbuffer(GL_RENDERBUFFER, 0);
      }
    }
  }
};

XrProgram::XrProgram(const std::string& appName) : m(std::make_unique<Impl>()) {
  std::uint32_t count = 0;
  XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr);
  if (XR_FAILED(r))
    throw XrUnavailable("no OpenXR runtime (" + resultName(XR_NULL_HANDLE, r) + ")");
  std::vector<XrExtensionProperties> props(count, {XR_TYPE_EXTENSION_PROPERTIES});
  check(XR_NULL_HANDLE, xrEnumerateInstanceExtensionProperties(nullptr, count, &count, props.data()),
        "xrEnumerateInstanceExtensionProperties");
  auto has = [&](const char* name) {
    return std::any_of(props.begin(), props.end(), [&](const XrExtensionProperties& p) {
      return std::strcmp(p.extensionName, name) == 0;
    });
  };
  if (!has(XR_KHR_OPENGL_ENABLE_EXTENSION_NAME))
    throw XrUnavailable("the OpenXR runtime has no OpenGL support (XR_KHR_opengl_enable)");
  std::vector<const char*> enabled = {XR_KHR_OPENGL_ENABLE_EXTENSION_NAME};
  m->handExt = has(XR_EXT_HAND_TRACKING_EXTENSION_NAME);
  m->depthExt = has(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
  if (m->handExt)
    enabled.push_back(XR_EXT_HAND_TRACKING_EXTENSION_NAME);
  if (m->depthExt)
    enabled.push_back(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
  XrInstanceCreateInfo info{XR_TYPE_INSTANCE_CREATE_INFO};
  std::snprintf(info.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "%s", appName.c_str());
  std::snprintf(info.applicationInfo.engineName, XR_MAX_ENGINE_NAME_SIZE, "FluidPlaying");
  info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  info.enabledExtensionCount = std::uint32_t(enabled.size());
  info.enabledExtensionNames = enabled.data();
  check(XR_NULL_HANDLE, xrCreateInstance(&info, &m->instance), "xrCreateInstance");
  XrSystemGetInfo system{XR_TYPE_SYSTEM_GET_INFO};
  system.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  r = xrGetSystem(m->instance, &system, &m->system);
  if (XR_FAILED(r)) {
    const std::string name = resultName(m->instance, r);
    xrDestroyInstance(m->instance);
    m->instance = XR_NULL_HANDLE;
    throw XrUnavailable("no head-mounted display (" + name + ")");
  }
  XrInstanceProperties ip{XR_TYPE_INSTANCE_PROPERTIES};
  xrGetInstanceProperties(m->instance, &ip);
  XrSystemHandTrackingPropertiesEXT hands{XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT};
  XrSystemProperties sp{XR_TYPE_SYSTEM_PROPERTIES, m->handExt ? &hands : nullptr};
  check(m->instance, xrGetSystemProperties(m->instance, m->system, &sp), "xrGetSystemProperties");
  m->handExt = m->handExt && hands.supportsHandTracking;
  m_description = std::string(ip.runtimeName) + ", " + sp.systemName;
  std::uint32_t n = 0;
  m->configs.fill({XR_TYPE_VIEW_CONFIGURATION_VIEW});
  check(m->instance,
        xrEnumerateViewConfigurationViews(m->instance, m->system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO,
                                          2, &n, m->configs.data()),
        "xrEnumerateViewConfigurationViews (primary stereo)");
  PFN_xrGetOpenGLGraphicsRequirementsKHR requirements = nullptr;
  check(m->instance,
        xrGetInstanceProcAddr(m->instance, "xrGetOpenGLGraphicsRequirementsKHR",
                              reinterpret_cast<PFN_xrVoidFunction*>(&requirements)),
        "xrGetOpenGLGraphicsRequirementsKHR");
  check(m->instance, requirements(m->instance, m->system, &m->requirements),
        "xrGetOpenGLGraphicsRequirementsKHR");
  if (m->handExt) {
    xrGetInstanceProcAddr(m->instance, "xrCreateHandTrackerEXT",
                          reinterpret_cast<PFN_xrVoidFunction*>(&m->createHandTracker));
    xrGetInstanceProcAddr(m->instance, "xrDestroyHandTrackerEXT",
                          reinterpret_cast<PFN_xrVoidFunction*>(&m->destroyHandTracker));
    xrGetInstanceProcAddr(m->instance, "xrLocateHandJointsEXT",
                          reinterpret_cast<PFN_xrVoidFunction*>(&m->locateHandJoints));
    m->handExt = m->createHandTracker && m->destroyHandTracker && m->locateHandJoints;
  }
}

XrProgram::~XrProgram() {
  m->destroySession();
  if (m->instance != XR_NULL_HANDLE)
    xrDestroyInstance(m->instance);
}

std::array<int, 2> XrProgram::recommendedSize() const {
  return {int(m->configs[0].recommendedImageRectWidth), int(m->configs[0].recommendedImageRectHeight)};
}

std::string XrProgram::glRequirement() const {
  auto v = [](XrVersion x) {
    return std::to_string(XR_VERSION_MAJOR(x)) + "." + std::to_string(XR_VERSION_MINOR(x));
  };
  return v(m->requirements.minApiVersionSupported) + " - " + v(m->requirements.maxApiVersionSupported);
}

bool XrProgram::hasSession() const {
  return m->session != XR_NULL_HANDLE;
}

bool XrProgram::sessionRunning() const {
  return m->session != XR_NULL_HANDLE && m->running;
}

bool XrProgram::stageSpace() const {
  return m->stage;
}

void XrProgram::createSession(const GlxBinding& binding) {
  XrGraphicsBindingOpenGLXlibKHR gl{XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR};
  gl.xDisplay = static_cast<Display*>(binding.display);
  gl.glxFBConfig = static_cast<GLXFBConfig>(binding.fbConfig);
  gl.glxDrawable = GLXDrawable(binding.drawable);
  gl.glxContext = static_cast<GLXContext>(binding.context);
  XrSessionCreateInfo info{XR_TYPE_SESSION_CREATE_INFO};
  info.next = &gl;
  info.systemId = m->system;
  check(m->instance, xrCreateSession(m->instance, &info, &m->session), "xrCreateSession");
  try {
    std::uint32_t count = 0;
    check(m->instance, xrEnumerateReferenceSpaces(m->session, 0, &count, nullptr),
          "xrEnumerateReferenceSpaces");
    std::vector<XrReferenceSpaceType> types(count);
    check(m->instance, xrEnumerateReferenceSpaces(m->session, count, &count, types.data()),
          "xrEnumerateReferenceSpaces");
    m->stage = std::find(types.begin(), types.end(), XR_REFERENCE_SPACE_TYPE_STAGE) != types.end();
    XrReferenceSpaceCreateInfo space{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
    space.referenceSpaceType = m->stage ? XR_REFERENCE_SPACE_TYPE_STAGE : XR_REFERENCE_SPACE_TYPE_LOCAL;
    space.poseInReferenceSpace = kIdentity;
    check(m->instance, xrCreateReferenceSpace(m->session, &space, &m->space), "xrCreateReferenceSpace");
    space.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
    check(m->instance, xrCreateReferenceSpace(m->session, &space, &m->view), "xrCreateReferenceSpace (VIEW)");
    m->createSwapchains();
    m->createActions();
    if (m->handExt) {
      for (int h = 0; h < 2; ++h) {
        XrHandTrackerCreateInfoEXT t{XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT};
        t.hand = h == 0 ? XR_HAND_LEFT_EXT : XR_HAND_RIGHT_EXT;
        t.handJointSet = XR_HAND_JOINT_SET_DEFAULT_EXT;
        check(m->instance, m->createHandTracker(m->session, &t, &m->trackers[h]), "xrCreateHandTrackerEXT");
      }
    }
  } catch (...) {
    m->destroySession();
    throw;
  }
}

XrLifecycle XrProgram::pollEvents() {
  XrEventDataBuffer e{XR_TYPE_EVENT_DATA_BUFFER};
  XrLifecycle result = XrLifecycle::Idle;
  while (xrPollEvent(m->instance, &e) == XR_SUCCESS) {
    if (e.type == XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING) {
      m->destroySession();
      return XrLifecycle::Exit;
    }
    if (e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED) {
      const auto* s = reinterpret_cast<const XrEventDataSessionStateChanged*>(&e);
      if (s->session != m->session)
        continue;
      m->state = s->state;
      switch (s->state) {
        case XR_SESSION_STATE_READY: {
          XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
          begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
          check(m->instance, xrBeginSession(m->session, &begin), "xrBeginSession");
          m->running = true;
          break;
        }
        case XR_SESSION_STATE_STOPPING:
          check(m->instance, xrEndSession(m->session), "xrEndSession");
          m->running = false;
          break;
        case XR_SESSION_STATE_LOSS_PENDING:
          m->destroySession();
          return XrLifecycle::Recreate;
        case XR_SESSION_STATE_EXITING:
          m->destroySession();
          return XrLifecycle::Exit;
        default:
          break;
      }
    }
    e = {XR_TYPE_EVENT_DATA_BUFFER};
  }
  if (m->session == XR_NULL_HANDLE)
    return XrLifecycle::Exit;
  result = m->running ? XrLifecycle::Running : XrLifecycle::Idle;
  return result;
}

void XrProgram::requestExit() {
  if (m->session != XR_NULL_HANDLE && m->running)
    xrRequestExitSession(m->session);
}

XrProgram::FrameTiming XrProgram::beginFrame() {
  m->frame = {XR_TYPE_FRAME_STATE};
  XrFrameWaitInfo wait{XR_TYPE_FRAME_WAIT_INFO};
  check(m->instance, xrWaitFrame(m->session, &wait, &m->frame), "xrWaitFrame");
  XrFrameBeginInfo begin{XR_TYPE_FRAME_BEGIN_INFO};
  check(m->instance, xrBeginFrame(m->session, &begin), "xrBeginFrame");
  FrameTiming t;
  t.displayTime = m->frame.predictedDisplayTime;
  t.period = double(m->frame.predictedDisplayPeriod) * 1e-9;
  t.shouldRender = m->frame.shouldRender == XR_TRUE;
  return t;
}

std::array<XrEyeView, 2> XrProgram::locateEyes() {
  XrViewLocateInfo info{XR_TYPE_VIEW_LOCATE_INFO};
  info.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  info.displayTime = m->frame.predictedDisplayTime;
  info.space = m->space;
  XrViewState state{XR_TYPE_VIEW_STATE};
  std::uint32_t n = 0;
  m->views = {{{XR_TYPE_VIEW}, {XR_TYPE_VIEW}}};
  check(m->instance, xrLocateViews(m->session, &info, &state, 2, &n, m->views.data()), "xrLocateViews");
  std::array<XrEyeView, 2> out;
  for (int i = 0; i < 2; ++i) {
    const XrView& v = m->views[i];
    XrEyeView& e = out[i];
    e.position = Eigen::Vector3f(v.pose.position.x, v.pose.position.y, v.pose.position.z);
    e.orientation = Eigen::Quaternionf(v.pose.orientation.w, v.pose.orientation.x, v.pose.orientation.y,
                                       v.pose.orientation.z)
                        .normalized();
    e.view = render::viewFromPose(e.position, e.orientation);
    e.fov = {v.fov.angleLeft, v.fov.angleRight, v.fov.angleUp, v.fov.angleDown};
    e.width = m->eyes[i].width;
    e.height = m->eyes[i].height;
  }
  return out;
}

unsigned XrProgram::acquireEye(int eye) {
  Eye& e = m->eyes[eye];
  XrSwapchainImageAcquireInfo acquire{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
  XrSwapchainImageWaitInfo wait{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
  wait.timeout = XR_INFINITE_DURATION;
  check(m->instance, xrAcquireSwapchainImage(e.color, &acquire, &e.colorIndex), "xrAcquireSwapchainImage");
  check(m->instance, xrWaitSwapchainImage(e.color, &wait), "xrWaitSwapchainImage");
  glBindFramebuffer(GL_FRAMEBUFFER, e.framebuffer);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                         e.colorImages[e.colorIndex].image, 0);
  if (e.depth != XR_NULL_HANDLE) {
    check(m->instance, xrAcquireSwapchainImage(e.depth, &acquire, &e.depthIndex), "xrAcquireSwapchainImage");
    check(m->instance, xrWaitSwapchainImage(e.depth, &wait), "xrWaitSwapchainImage");
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D,
                           e.depthImages[e.depthIndex].image, 0);
  } else {
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e.depthBuffer);
  }
  return e.framebuffer;
}

void XrProgram::releaseEye(int eye) {
  Eye& e = m->eyes[eye];
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  XrSwapchainImageReleaseInfo release{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
  check(m->instance, xrReleaseSwapchainImage(e.color, &release), "xrReleaseSwapchainImage");
  if (e.depth != XR_NULL_HANDLE)
    check(m->instance, xrReleaseSwapchainImage(e.depth, &release), "xrReleaseSwapchainImage");
}

void XrProgram::endFrame(bool rendered, float nearZ, float farZ) {
  std::array<XrCompositionLayerProjectionView, 2> views{
      {{XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW}, {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW}}};
  std::array<XrCompositionLayerDepthInfoKHR, 2> depth{
      {{XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR}, {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR}}};
  for (int i = 0; i < 2; ++i) {
    const Eye& e = m->eyes[i];
    views[i].pose = m->views[i].pose;
    views[i].fov = m->views[i].fov;
    views[i].subImage.swapchain = e.color;
    views[i].subImage.imageRect = {{0, 0}, {e.width, e.height}};
    if (e.depth != XR_NULL_HANDLE) {
      depth[i].subImage.swapchain = e.depth;
      depth[i].subImage.imageRect = {{0, 0}, {e.width, e.height}};
      depth[i].minDepth = 0.0f;
      depth[i].maxDepth = 1.0f;
      depth[i].nearZ = nearZ;
      depth[i].farZ = farZ;
      views[i].next = &depth[i];
    }
  }
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  layer.space = m->space;
  layer.viewCount = 2;
  layer.views = views.data();
  const XrCompositionLayerBaseHeader* layers[] = {
      reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
  XrFrameEndInfo end{XR_TYPE_FRAME_END_INFO};
  end.displayTime = m->frame.predictedDisplayTime;
  end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  end.layerCount = rendered ? 1 : 0;
  end.layers = layers;
  check(m->instance, xrEndFrame(m->session, &end), "xrEndFrame");
}

XrHands XrProgram::locateHands() {
  XrHands out;
  const XrTime time = m->frame.predictedDisplayTime;
  XrActiveActionSet active{m->actionSet, XR_NULL_PATH};
  XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
  sync.countActiveActionSets = 1;
  sync.activeActionSets = &active;
  check(m->instance, xrSyncActions(m->session, &sync), "xrSyncActions");
  bool menu = false;
  for (int h = 0; h < 2; ++h) {
    XrActionStateGetInfo get{XR_TYPE_ACTION_STATE_GET_INFO};
    get.subactionPath = m->handPaths[h];
    get.action = m->menuAction;
    XrActionStateBoolean menuState{XR_TYPE_ACTION_STATE_BOOLEAN};
    if (XR_SUCCEEDED(xrGetActionStateBoolean(m->session, &get, &menuState)))
      menu |= menuState.isActive && menuState.currentState;
    if (m->handExt) {
      XrHandJointLocationEXT locations[XR_HAND_JOINT_COUNT_EXT];
      XrHandJointLocationsEXT all{XR_TYPE_HAND_JOINT_LOCATIONS_EXT};
      all.jointCount = XR_HAND_JOINT_COUNT_EXT;
      all.jointLocations = locations;
      XrHandJointsLocateInfoEXT info{XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT};
      info.baseSpace = m->space;
      info.time = time;
      check(m->instance, m->locateHandJoints(m->trackers[h], &info, &all), "xrLocateHandJointsEXT");
      const XrSpaceLocationFlags needed =
          XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
      bool valid = all.isActive == XR_TRUE;
      for (int j = 0; valid && j < XR_HAND_JOINT_COUNT_EXT; ++j)
        valid = (locations[j].locationFlags & needed) == needed;
      if (valid) {
        input::HandJoints joints;
        joints.valid = true;
        for (int j = 0; j < XR_HAND_JOINT_COUNT_EXT; ++j) {
          joints.joint[j].position = toVec(locations[j].pose.position);
          joints.joint[j].orientation = toQuat(locations[j].pose.orientation);
          joints.joint[j].radius = std::max(1e-3, double(locations[j].radius));
        }
        out.joints[h] = joints;
      }
      continue;
    }
    // no hand tracking: the controller drives the model hand
    out.fromControllers = true;
    get.action = m->gripAction;
    XrActionStatePose pose{XR_TYPE_ACTION_STATE_POSE};
    check(m->instance, xrGetActionStatePose(m->session, &get, &pose), "xrGetActionStatePose");
    if (!pose.isActive)
      continue;
    XrSpaceLocation where{XR_TYPE_SPACE_LOCATION};
    check(m->instance, xrLocateSpace(m->gripSpaces[h], m->space, time, &where), "xrLocateSpace");
    const XrSpaceLocationFlags needed =
        XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
    if ((where.locationFlags & needed) != needed)
      continue;
    float values[2] = {0.0f, 0.0f};
    const XrAction analog[2] = {m->triggerAction, m->squeezeAction};
    for (int k = 0; k < 2; ++k) {
      get.action = analog[k];
      XrActionStateFloat v{XR_TYPE_ACTION_STATE_FLOAT};
      if (XR_SUCCEEDED(xrGetActionStateFloat(m->session, &get, &v)) && v.isActive)
        values[k] = v.currentState;
    }
    const input::HandSide side = h == 0 ? input::HandSide::Left : input::HandSide::Right;
    const input::HandPose hand = input::controllerHandPose(
        toVec(where.pose.position), toQuat(where.pose.orientation), values[0], values[1], side);
    out.joints[h] = input::jointsOfHandPose(input::HandModel(), hand, side);
  }
  out.recentre = menu && !m->menuWasDown;
  m->menuWasDown = menu;
  return out;
}

std::pair<Eigen::Vector3f, Eigen::Quaternionf> XrProgram::headPose() {
  XrSpaceLocation where{XR_TYPE_SPACE_LOCATION};
  check(m->instance, xrLocateSpace(m->view, m->space, m->frame.predictedDisplayTime, &where),
        "xrLocateSpace");
  return {Eigen::Vector3f(where.pose.position.x, where.pose.position.y, where.pose.position.z),
          Eigen::Quaternionf(where.pose.orientation.w, where.pose.orientation.x, where.pose.orientation.y,
                             where.pose.orientation.z)
              .normalized()};
}

}  // namespace fp::engine
