// The test OpenXR runtime driven directly through the Khronos loader, with the core validation layer on:
// instance -> system -> GL session -> frames -> exit, hand joints and controller actions, the error codes of
// misuse, and an OpenXR runtime's GL lookups in a process where render/gl_api replaced glXGetProcAddressARB.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include "input/joint_track.h"
// X11 last: its macros (Success, None) clash with Eigen
#include "tests/xr/xr_test_env.h"

#define XR_USE_GRAPHICS_API_OPENGL
#define XR_USE_PLATFORM_XLIB
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

namespace fp {
namespace {

#define XR_OK(call) ASSERT_EQ((call), XR_SUCCESS) << #call

std::string testDir(const char* name) {
  return (std::filesystem::temp_directory_path() / "fp_xr_runtime_test" / name).string();
}

class XrRuntime : public ::testing::Test {
 protected:
  void SetUp() override {
    m_validation =
        test::useTestRuntime(testDir(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    m_stats = testDir(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "/stats.txt";
    std::filesystem::remove(m_stats);
    setenv("FP_XR_STATS", m_stats.c_str(), 1);
    setenv("FP_XR_VIRTUAL_TIME", "1", 1);
  }
  void TearDown() override {
    if (m_session != XR_NULL_HANDLE)
      xrDestroySession(m_session);
    if (m_instance != XR_NULL_HANDLE)
      xrDestroyInstance(m_instance);
    if (m_checkValidation) {
      EXPECT_EQ(test::validationMessages(m_validation), "");
    }
  }

  /// instance with the GL, hand-tracking and depth extensions the runtime offers
  void createInstance() {
    uint32_t count = 0;
    XR_OK(xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr));
    std::vector<XrExtensionProperties> props(count, {XR_TYPE_EXTENSION_PROPERTIES});
    XR_OK(xrEnumerateInstanceExtensionProperties(nullptr, count, &count, props.data()));
    std::vector<const char*> names;
    for (const auto& p : props) {
      for (const char* wanted : {XR_KHR_OPENGL_ENABLE_EXTENSION_NAME, XR_EXT_HAND_TRACKING_EXTENSION_NAME,
                                 XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME}) {
        if (std::strcmp(p.extensionName, wanted) == 0)
          names.push_back(wanted);
      }
    }
    m_hasHands = std::any_of(props.begin(), props.end(), [](const XrExtensionProperties& p) {
      return std::strcmp(p.extensionName, XR_EXT_HAND_TRACKING_EXTENSION_NAME) == 0;
    });
    XrInstanceCreateInfo info{XR_TYPE_INSTANCE_CREATE_INFO};
    std::snprintf(info.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "fp_test_xr_runtime");
    info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
    info.enabledExtensionCount = uint32_t(names.size());
    info.enabledExtensionNames = names.data();
    XR_OK(xrCreateInstance(&info, &m_instance));
    XrSystemGetInfo system{XR_TYPE_SYSTEM_GET_INFO};
    system.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
    XR_OK(xrGetSystem(m_instance, &system, &m_system));
  }

  template <class F>
  F proc(const char* name) {
    PFN_xrVoidFunction f = nullptr;
    EXPECT_EQ(xrGetInstanceProcAddr(m_instance, name, &f), XR_SUCCESS) << name;
    return reinterpret_cast<F>(f);
  }

  void createSession() {
    std::string error;
    if (!m_gl.create(error))
      GTEST_SKIP() << error;
    XrGraphicsRequirementsOpenGLKHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_OPENGL_KHR};
    XR_OK(proc<PFN_xrGetOpenGLGraphicsRequirementsKHR>("xrGetOpenGLGraphicsRequirementsKHR")(m_instance,
                                                                                             m_system, &req));
    XrGraphicsBindingOpenGLXlibKHR binding{XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR};
    binding.xDisplay = m_gl.display;
    binding.glxFBConfig = m_gl.config;
    binding.glxDrawable = m_gl.drawable;
    binding.glxContext = m_gl.context;
    XrSessionCreateInfo info{XR_TYPE_SESSION_CREATE_INFO};
    info.next = &binding;
    info.systemId = m_system;
    XR_OK(xrCreateSession(m_instance, &info, &m_session));
  }

  /// polls every queued event; returns the last session state seen (or `current`)
  XrSessionState poll(XrSessionState current) {
    XrEventDataBuffer e{XR_TYPE_EVENT_DATA_BUFFER};
    while (xrPollEvent(m_instance, &e) == XR_SUCCESS) {
      if (e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED)
        current = reinterpret_cast<XrEventDataSessionStateChanged*>(&e)->state;
      e = {XR_TYPE_EVENT_DATA_BUFFER};
    }
    return current;
  }

  XrSwapchain swapchain(int64_t format, uint32_t w, uint32_t h, XrSwapchainUsageFlags usage) {
    XrSwapchainCreateInfo info{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    info.usageFlags = usage;
    info.format = format;
    info.sampleCount = 1;
    info.width = w;
    info.height = h;
    info.faceCount = 1;
    info.arraySize = 1;
    info.mipCount = 1;
    XrSwapchain sc = XR_NULL_HANDLE;
    EXPECT_EQ(xrCreateSwapchain(m_session, &info, &sc), XR_SUCCESS);
    return sc;
  }

  XrInstance m_instance = XR_NULL_HANDLE;
  XrSystemId m_system = XR_NULL_SYSTEM_ID;
  XrSession m_session = XR_NULL_HANDLE;
  test::GlxContext m_gl;
  std::string m_validation;
  std::string m_stats;
  bool m_hasHands = false;
  bool m_checkValidation = true;
};

TEST_F(XrRuntime, SessionFramesAndExit) {
  setenv("FP_XR_SIZE", "160,120", 1);
  createInstance();
  ASSERT_TRUE(m_hasHands);
  XrSystemHandTrackingPropertiesEXT hands{XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT};
  XrSystemProperties props{XR_TYPE_SYSTEM_PROPERTIES, &hands};
  XR_OK(xrGetSystemProperties(m_instance, m_system, &props));
  EXPECT_TRUE(hands.supportsHandTracking);
  uint32_t viewCount = 0;
  XR_OK(xrEnumerateViewConfigurationViews(m_instance, m_system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0,
                                          &viewCount, nullptr));
  ASSERT_EQ(viewCount, 2u);
  std::vector<XrViewConfigurationView> configs(2, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
  XR_OK(xrEnumerateViewConfigurationViews(m_instance, m_system, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 2,
                                          &viewCount, configs.data()));
  EXPECT_EQ(configs[0].recommendedImageRectWidth, 160u);
  EXPECT_EQ(configs[0].recommendedImageRectHeight, 120u);
  createSession();
  if (IsSkipped())
    return;
  // not READY before the application has seen the event
  XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
  begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  EXPECT_EQ(xrBeginSession(m_session, &begin), XR_ERROR_SESSION_NOT_READY);
  ASSERT_EQ(poll(XR_SESSION_STATE_UNKNOWN), XR_SESSION_STATE_READY);
  XR_OK(xrBeginSession(m_session, &begin));
  EXPECT_EQ(xrBeginSession(m_session, &begin), XR_ERROR_SESSION_RUNNING);

  uint32_t formatCount = 0;
  XR_OK(xrEnumerateSwapchainFormats(m_session, 0, &formatCount, nullptr));
  std::vector<int64_t> formats(formatCount);
  XR_OK(xrEnumerateSwapchainFormats(m_session, formatCount, &formatCount, formats.data()));
  ASSERT_EQ(formats[0], GL_SRGB8_ALPHA8);
  XrSwapchainCreateInfo bad{XR_TYPE_SWAPCHAIN_CREATE_INFO};
  bad.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT;
  bad.format = GL_RGB565;  // not offered
  bad.sampleCount = bad.faceCount = bad.arraySize = bad.mipCount = 1;
  bad.width = bad.height = 64;
  XrSwapchain none = XR_NULL_HANDLE;
  EXPECT_EQ(xrCreateSwapchain(m_session, &bad, &none), XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED);

  XrReferenceSpaceCreateInfo spaceInfo{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  spaceInfo.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
  spaceInfo.poseInReferenceSpace.orientation.w = 1.0f;
  XrSpace stage = XR_NULL_HANDLE;
  XR_OK(xrCreateReferenceSpace(m_session, &spaceInfo, &stage));

  XrSwapchain color[2], depth[2];
  std::vector<XrSwapchainImageOpenGLKHR> images[2];
  for (int eye = 0; eye < 2; ++eye) {
    color[eye] = swapchain(formats[0], 160, 120, XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT);
    depth[eye] = swapchain(GL_DEPTH_COMPONENT24, 160, 120, XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT);
    uint32_t n = 0;
    XR_OK(xrEnumerateSwapchainImages(color[eye], 0, &n, nullptr));
    images[eye].assign(n, {XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR});
    XR_OK(xrEnumerateSwapchainImages(color[eye], n, &n,
                                     reinterpret_cast<XrSwapchainImageBaseHeader*>(images[eye].data())));
    for (const auto& image : images[eye])
      EXPECT_TRUE(glIsTexture(image.image)) << "the runtime's textures live in the app's GL context";
  }
  // the frame calls in the wrong order
  EXPECT_EQ(xrBeginFrame(m_session, nullptr), XR_ERROR_CALL_ORDER_INVALID);
  const uint32_t dummy = 0;
  (void)dummy;
  XrSwapchainImageReleaseInfo releaseInfo{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
  EXPECT_EQ(xrReleaseSwapchainImage(color[0], &releaseInfo), XR_ERROR_CALL_ORDER_INVALID);

  XrSessionState state = XR_SESSION_STATE_READY;
  const int frames = 12;
  XrTime lastDisplay = 0;
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  for (int f = 0; f < frames; ++f) {
    state = poll(state);
    XrFrameWaitInfo waitInfo{XR_TYPE_FRAME_WAIT_INFO};
    XrFrameState frame{XR_TYPE_FRAME_STATE};
    XR_OK(xrWaitFrame(m_session, &waitInfo, &frame));
    EXPECT_EQ(frame.predictedDisplayPeriod, 11111111);
    if (lastDisplay) {
      EXPECT_EQ(frame.predictedDisplayTime - lastDisplay, frame.predictedDisplayPeriod);
    }
    lastDisplay = frame.predictedDisplayTime;
    XrFrameBeginInfo beginInfo{XR_TYPE_FRAME_BEGIN_INFO};
    XR_OK(xrBeginFrame(m_session, &beginInfo));
    XrViewLocateInfo locate{XR_TYPE_VIEW_LOCATE_INFO};
    locate.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
    locate.displayTime = frame.predictedDisplayTime;
    locate.space = stage;
    XrViewState viewState{XR_TYPE_VIEW_STATE};
    XrView views[2] = {{XR_TYPE_VIEW}, {XR_TYPE_VIEW}};
    uint32_t n = 0;
    XR_OK(xrLocateViews(m_session, &locate, &viewState, 2, &n, views));
    EXPECT_NEAR(views[1].pose.position.x - views[0].pose.position.x, 0.064f, 1e-5f);
    EXPECT_NEAR(views[0].pose.position.y, 1.6f, 1e-5f);
    EXPECT_LT(views[0].fov.angleLeft, -views[0].fov.angleRight) << "asymmetric";
    XrCompositionLayerProjectionView proj[2] = {{XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW},
                                                {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW}};
    XrCompositionLayerDepthInfoKHR depthInfo[2] = {{XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR},
                                                   {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR}};
    for (int eye = 0; eye < 2; ++eye) {
      uint32_t index = 0, depthIndex = 0;
      XrSwapchainImageAcquireInfo acquire{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
      XR_OK(xrAcquireSwapchainImage(color[eye], &acquire, &index));
      XR_OK(xrAcquireSwapchainImage(depth[eye], &acquire, &depthIndex));
      XrSwapchainImageWaitInfo wait{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
      wait.timeout = XR_INFINITE_DURATION;
      XR_OK(xrWaitSwapchainImage(color[eye], &wait));
      XR_OK(xrWaitSwapchainImage(depth[eye], &wait));
      glBindFramebuffer(GL_FRAMEBUFFER, fbo);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, images[eye][index].image,
                             0);
      EXPECT_EQ(glCheckFramebufferStatus(GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
      glClearColor(0.2f * float(eye), 0.5f, 0.8f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      XR_OK(xrReleaseSwapchainImage(color[eye], &releaseInfo));
      XR_OK(xrReleaseSwapchainImage(depth[eye], &releaseInfo));
      proj[eye].pose = views[eye].pose;
      proj[eye].fov = views[eye].fov;
      proj[eye].subImage.swapchain = color[eye];
      proj[eye].subImage.imageRect = {{0, 0}, {160, 120}};
      depthInfo[eye].subImage.swapchain = depth[eye];
      depthInfo[eye].subImage.imageRect = {{0, 0}, {160, 120}};
      depthInfo[eye].minDepth = 0.0f;
      depthInfo[eye].maxDepth = 1.0f;
      depthInfo[eye].nearZ = 0.05f;
      depthInfo[eye].farZ = 50.0f;
      proj[eye].next = &depthInfo[eye];
    }
    XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
    layer.space = stage;
    layer.viewCount = 2;
    layer.views = proj;
    const XrCompositionLayerBaseHeader* layers[] = {reinterpret_cast<XrCompositionLayerBaseHeader*>(&layer)};
    XrFrameEndInfo end{XR_TYPE_FRAME_END_INFO};
    end.displayTime = frame.predictedDisplayTime;
    end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    end.layerCount = frame.shouldRender ? 1 : 0;
    end.layers = layers;
    XR_OK(xrEndFrame(m_session, &end));
    EXPECT_EQ(xrEndFrame(m_session, &end), XR_ERROR_CALL_ORDER_INVALID) << "a second end of one frame";
  }
  glDeleteFramebuffers(1, &fbo);
  EXPECT_EQ(state, XR_SESSION_STATE_FOCUSED);
  EXPECT_EQ(xrEndSession(m_session), XR_ERROR_SESSION_NOT_STOPPING);
  XR_OK(xrRequestExitSession(m_session));
  ASSERT_EQ(poll(state), XR_SESSION_STATE_STOPPING);
  XR_OK(xrEndSession(m_session));
  EXPECT_EQ(poll(XR_SESSION_STATE_STOPPING), XR_SESSION_STATE_EXITING);
  for (int eye = 0; eye < 2; ++eye) {
    XR_OK(xrDestroySwapchain(color[eye]));
    XR_OK(xrDestroySwapchain(depth[eye]));
  }
  XR_OK(xrDestroySpace(stage));
  XR_OK(xrDestroySession(m_session));
  m_session = XR_NULL_HANDLE;
  EXPECT_EQ(test::runtimeStat(m_stats, "submitted"), frames);
  EXPECT_EQ(test::runtimeStat(m_stats, "ended"), 1);
}

TEST_F(XrRuntime, HandJointsAndControllerActions) {
  // a recording of both hands, played by the runtime 1 m above the recording's origin
  const std::string joints = testDir("HandJointsAndControllerActions") + "/hands.csv";
  input::JointTrack track;
  for (int k = 0; k < 3; ++k) {
    input::JointFrame f;
    f.time = 0.5 * k;
    input::HandPose pose;
    pose.position = sim::Vec3d(0.1 * k, 0.0, -0.3);
    f.hands[0] = input::jointsOfHandPose(input::HandModel(), pose, input::HandSide::Left);
    f.hands[1] = input::jointsOfHandPose(input::HandModel(), pose, input::HandSide::Right);
    track.add(f);
  }
  track.save(joints);
  setenv("FP_XR_HANDS", joints.c_str(), 1);
  setenv("FP_XR_HANDS_OFFSET", "0,1,0", 1);
  setenv("FP_XR_EVENTS", "3:lost_right", 1);
  setenv("FP_XR_PROFILE", "/interaction_profiles/valve/index_controller", 1);
  setenv("FP_XR_CONTROLLERS", "0.25,0.75", 1);
  createInstance();
  createSession();
  if (IsSkipped())
    return;
  auto path = [&](const char* s) {
    XrPath p = XR_NULL_PATH;
    EXPECT_EQ(xrStringToPath(m_instance, s, &p), XR_SUCCESS);
    return p;
  };
  XrActionSetCreateInfo setInfo{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::strcpy(setInfo.actionSetName, "hands");
  std::strcpy(setInfo.localizedActionSetName, "Hands");
  XrActionSet set = XR_NULL_HANDLE;
  XR_OK(xrCreateActionSet(m_instance, &setInfo, &set));
  const XrPath handPaths[2] = {path("/user/hand/left"), path("/user/hand/right")};
  auto action = [&](const char* name, XrActionType type) {
    XrActionCreateInfo info{XR_TYPE_ACTION_CREATE_INFO};
    std::strcpy(info.actionName, name);
    std::strcpy(info.localizedActionName, name);
    info.actionType = type;
    info.countSubactionPaths = 2;
    info.subactionPaths = handPaths;
    XrAction a = XR_NULL_HANDLE;
    EXPECT_EQ(xrCreateAction(set, &info, &a), XR_SUCCESS);
    return a;
  };
  const XrAction grip = action("grip", XR_ACTION_TYPE_POSE_INPUT);
  const XrAction trigger = action("trigger", XR_ACTION_TYPE_FLOAT_INPUT);
  const XrAction squeeze = action("squeeze", XR_ACTION_TYPE_FLOAT_INPUT);
  std::vector<XrActionSuggestedBinding> bindings = {{grip, path("/user/hand/left/input/grip/pose")},
                                                    {grip, path("/user/hand/right/input/grip/pose")},
                                                    {trigger, path("/user/hand/left/input/trigger/value")},
                                                    {trigger, path("/user/hand/right/input/trigger/value")},
                                                    {squeeze, path("/user/hand/left/input/squeeze/value")},
                                                    {squeeze, path("/user/hand/right/input/squeeze/value")}};
  XrInteractionProfileSuggestedBinding suggested{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
  suggested.interactionProfile = path("/interaction_profiles/valve/index_controller");
  suggested.countSuggestedBindings = uint32_t(bindings.size());
  suggested.suggestedBindings = bindings.data();
  XR_OK(xrSuggestInteractionProfileBindings(m_instance, &suggested));
  // the simple controller has no trigger value
  const XrActionSuggestedBinding wrong = {trigger, path("/user/hand/left/input/trigger/value")};
  suggested.interactionProfile = path("/interaction_profiles/khr/simple_controller");
  suggested.countSuggestedBindings = 1;
  suggested.suggestedBindings = &wrong;
  EXPECT_EQ(xrSuggestInteractionProfileBindings(m_instance, &suggested), XR_ERROR_PATH_UNSUPPORTED);
  XrSessionActionSetsAttachInfo attach{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
  attach.countActionSets = 1;
  attach.actionSets = &set;
  XR_OK(xrAttachSessionActionSets(m_session, &attach));

  XrReferenceSpaceCreateInfo spaceInfo{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  spaceInfo.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
  spaceInfo.poseInReferenceSpace.orientation.w = 1.0f;
  XrSpace stage = XR_NULL_HANDLE;
  XR_OK(xrCreateReferenceSpace(m_session, &spaceInfo, &stage));
  XrActionSpaceCreateInfo gripInfo{XR_TYPE_ACTION_SPACE_CREATE_INFO};
  gripInfo.action = grip;
  gripInfo.subactionPath = handPaths[1];
  gripInfo.poseInActionSpace.orientation.w = 1.0f;
  XrSpace rightGrip = XR_NULL_HANDLE;
  XR_OK(xrCreateActionSpace(m_session, &gripInfo, &rightGrip));

  auto createTracker = proc<PFN_xrCreateHandTrackerEXT>("xrCreateHandTrackerEXT");
  auto locateJoints = proc<PFN_xrLocateHandJointsEXT>("xrLocateHandJointsEXT");
  auto destroyTracker = proc<PFN_xrDestroyHandTrackerEXT>("xrDestroyHandTrackerEXT");
  XrHandTrackerEXT trackers[2];
  for (int h = 0; h < 2; ++h) {
    XrHandTrackerCreateInfoEXT info{XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT};
    info.hand = h == 0 ? XR_HAND_LEFT_EXT : XR_HAND_RIGHT_EXT;
    info.handJointSet = XR_HAND_JOINT_SET_DEFAULT_EXT;
    XR_OK(createTracker(m_session, &info, &trackers[h]));
  }
  XrSessionState state = poll(XR_SESSION_STATE_UNKNOWN);
  ASSERT_EQ(state, XR_SESSION_STATE_READY);
  XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
  begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  XR_OK(xrBeginSession(m_session, &begin));
  for (int f = 1; f <= 4; ++f) {
    XrFrameState frame{XR_TYPE_FRAME_STATE};
    XR_OK(xrWaitFrame(m_session, nullptr, &frame));
    state = poll(state);
    XR_OK(xrBeginFrame(m_session, nullptr));
    XrActiveActionSet active{set, XR_NULL_PATH};
    XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
    sync.countActiveActionSets = 1;
    sync.activeActionSets = &active;
    XR_OK(xrSyncActions(m_session, &sync));
    XrActionStateGetInfo get{XR_TYPE_ACTION_STATE_GET_INFO};
    get.action = squeeze;
    get.subactionPath = handPaths[0];
    XrActionStateFloat value{XR_TYPE_ACTION_STATE_FLOAT};
    XR_OK(xrGetActionStateFloat(m_session, &get, &value));
    EXPECT_TRUE(value.isActive);
    EXPECT_FLOAT_EQ(value.currentState, 0.75f);
    get.action = grip;
    get.subactionPath = handPaths[1];
    XrActionStatePose pose{XR_TYPE_ACTION_STATE_POSE};
    XR_OK(xrGetActionStatePose(m_session, &get, &pose));
    EXPECT_EQ(bool(pose.isActive), f < 3) << f;  // the right hand is lost from frame 3
    get.action = trigger;
    XrActionStateBoolean wrongType{XR_TYPE_ACTION_STATE_BOOLEAN};
    EXPECT_EQ(xrGetActionStateBoolean(m_session, &get, &wrongType), XR_ERROR_ACTION_TYPE_MISMATCH);

    for (int h = 0; h < 2; ++h) {
      XrHandJointLocationEXT locations[XR_HAND_JOINT_COUNT_EXT];
      XrHandJointLocationsEXT all{XR_TYPE_HAND_JOINT_LOCATIONS_EXT};
      all.jointCount = XR_HAND_JOINT_COUNT_EXT;
      all.jointLocations = locations;
      XrHandJointsLocateInfoEXT info{XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT};
      info.baseSpace = stage;
      info.time = frame.predictedDisplayTime;
      XR_OK(locateJoints(trackers[h], &info, &all));
      const bool expected = h == 0 || f < 3;
      ASSERT_EQ(bool(all.isActive), expected) << h << " " << f;
      if (!expected)
        continue;
      // frame f is displayed f periods after the session began: the recording at that time, 1 m up
      const double t = f * 11111111e-9;
      const input::JointFrame rec = track.sample(t);
      for (int j = 0; j < XR_HAND_JOINT_COUNT_EXT; ++j) {
        const sim::Vec3d p = rec.hands[h].joint[j].position + sim::Vec3d(0, 1, 0);
        EXPECT_NEAR(locations[j].pose.position.x, p.x(), 1e-5);
        EXPECT_NEAR(locations[j].pose.position.y, p.y(), 1e-5);
        EXPECT_NEAR(locations[j].pose.position.z, p.z(), 1e-5);
        EXPECT_NEAR(locations[j].radius, rec.hands[h].joint[j].radius, 1e-6);
      }
      if (h == 1) {
        // the controller's grip sits on the palm
        XrSpaceLocation where{XR_TYPE_SPACE_LOCATION};
        XR_OK(xrLocateSpace(rightGrip, stage, frame.predictedDisplayTime, &where));
        EXPECT_NEAR(where.pose.position.x, locations[0].pose.position.x, 1e-5);
        EXPECT_NEAR(where.pose.position.z, locations[0].pose.position.z, 1e-5);
      }
    }
    XrFrameEndInfo end{XR_TYPE_FRAME_END_INFO};
    end.displayTime = frame.predictedDisplayTime;
    end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    XR_OK(xrEndFrame(m_session, &end));
  }
  for (XrHandTrackerEXT t : trackers)
    XR_OK(destroyTracker(t));
  XR_OK(xrDestroySpace(rightGrip));
  XR_OK(xrDestroySpace(stage));
  XR_OK(xrDestroyActionSet(set));
}

TEST_F(XrRuntime, SwitchesAndLossPending) {
  // no hand tracking: the extension is not offered
  setenv("FP_XR_NO_HANDS", "1", 1);
  setenv("FP_XR_EVENTS", "2:loss_pending", 1);
  createInstance();
  EXPECT_FALSE(m_hasHands);
  createSession();
  if (IsSkipped())
    return;
  XrSessionState state = poll(XR_SESSION_STATE_UNKNOWN);
  XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
  begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  XR_OK(xrBeginSession(m_session, &begin));
  for (int f = 0; f < 3; ++f) {
    XrFrameState frame{XR_TYPE_FRAME_STATE};
    XR_OK(xrWaitFrame(m_session, nullptr, &frame));
    XR_OK(xrBeginFrame(m_session, nullptr));
    XrFrameEndInfo end{XR_TYPE_FRAME_END_INFO};
    end.displayTime = frame.predictedDisplayTime;
    end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    XR_OK(xrEndFrame(m_session, &end));
    state = poll(state);
  }
  ASSERT_EQ(state, XR_SESSION_STATE_LOSS_PENDING);
  // the application destroys the lost session and makes a new one
  XR_OK(xrDestroySession(m_session));
  m_session = XR_NULL_HANDLE;
  XrGraphicsBindingOpenGLXlibKHR binding{XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR};
  binding.xDisplay = m_gl.display;
  binding.glxFBConfig = m_gl.config;
  binding.glxDrawable = m_gl.drawable;
  binding.glxContext = m_gl.context;
  XrSessionCreateInfo info{XR_TYPE_SESSION_CREATE_INFO, &binding, 0, m_system};
  XR_OK(xrCreateSession(m_instance, &info, &m_session));
  EXPECT_EQ(poll(XR_SESSION_STATE_UNKNOWN), XR_SESSION_STATE_READY);
  EXPECT_EQ(test::runtimeStat(m_stats, "sessions"), 1) << "written when the lost session was destroyed";
}

TEST_F(XrRuntime, NoHmdNoGl) {
  setenv("FP_XR_NO_HMD", "1", 1);
  setenv("FP_XR_NO_GL", "1", 1);
  uint32_t count = 0;
  XR_OK(xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr));
  std::vector<XrExtensionProperties> props(count, {XR_TYPE_EXTENSION_PROPERTIES});
  XR_OK(xrEnumerateInstanceExtensionProperties(nullptr, count, &count, props.data()));
  for (const auto& p : props)
    EXPECT_STRNE(p.extensionName, XR_KHR_OPENGL_ENABLE_EXTENSION_NAME);
  XrInstanceCreateInfo info{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(info.applicationInfo.applicationName, "fp_test");
  info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  const char* gl = XR_KHR_OPENGL_ENABLE_EXTENSION_NAME;
  info.enabledExtensionCount = 1;
  info.enabledExtensionNames = &gl;
  EXPECT_EQ(xrCreateInstance(&info, &m_instance), XR_ERROR_EXTENSION_NOT_PRESENT);
  m_instance = XR_NULL_HANDLE;
  info.enabledExtensionCount = 0;
  XR_OK(xrCreateInstance(&info, &m_instance));
  XrSystemGetInfo system{XR_TYPE_SYSTEM_GET_INFO};
  system.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  EXPECT_EQ(xrGetSystem(m_instance, &system, &m_system), XR_ERROR_FORM_FACTOR_UNAVAILABLE);
}

TEST_F(XrRuntime, WrongHandlesWithoutTheValidationLayer) {
  // the validation layer itself reports a handle the application never had: this misuse reaches the runtime
  // only without it
  unsetenv("XR_ENABLE_API_LAYERS");
  m_checkValidation = false;
  createInstance();
  createSession();
  if (IsSkipped())
    return;
  XrReferenceSpaceCreateInfo spaceInfo{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  spaceInfo.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_LOCAL;
  spaceInfo.poseInReferenceSpace.orientation.w = 1.0f;
  XrSpace space = XR_NULL_HANDLE;
  XR_OK(xrCreateReferenceSpace(m_session, &spaceInfo, &space));
  XR_OK(xrDestroySpace(space));
  EXPECT_EQ(xrDestroySpace(space), XR_ERROR_HANDLE_INVALID);
  XrSession stale = m_session;
  XR_OK(xrDestroySession(m_session));
  m_session = XR_NULL_HANDLE;
  XrFrameState frame{XR_TYPE_FRAME_STATE};
  EXPECT_EQ(xrWaitFrame(stale, nullptr, &frame), XR_ERROR_HANDLE_INVALID);
  XrSessionBeginInfo begin{XR_TYPE_SESSION_BEGIN_INFO};
  begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  EXPECT_EQ(xrBeginSession(stale, &begin), XR_ERROR_HANDLE_INVALID);
}

int g_appLookups = 0;
render::gl::Proc countingLoader(const char* name) {
  ++g_appLookups;
  return render::gl::glxProcAddress(name);
}

TEST_F(XrRuntime, RuntimeGlLookupsSurviveTheRenderersReplacement) {
  // render/gl_api replaces glXGetProcAddressARB for the whole process so GLEW asks the app's GL provider
  // (OSMesa, EGL, GLFW). A runtime in the same process resolves its own GL functions with
  // glXGetProcAddressARB (from its own threads and contexts, where the app's provider cannot answer): those
  // lookups must reach libGL, never the app's provider.
  createInstance();
  createSession();
  if (IsSkipped())
    return;
  render::gl::loadFunctions(&countingLoader);
  EXPECT_GT(g_appLookups, 100) << "GLEW's lookups go to the app's provider";
  g_appLookups = 0;
  XrSwapchain sc = swapchain(GL_RGBA8, 64, 32, XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT);
  ASSERT_NE(sc, XrSwapchain(XR_NULL_HANDLE));
  uint32_t n = 0;
  XR_OK(xrEnumerateSwapchainImages(sc, 0, &n, nullptr));
  std::vector<XrSwapchainImageOpenGLKHR> images(n, {XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR});
  XR_OK(xrEnumerateSwapchainImages(sc, n, &n, reinterpret_cast<XrSwapchainImageBaseHeader*>(images.data())));
  using IsTexture = GLboolean (*)(GLuint);
  using BindTexture = void (*)(GLenum, GLuint);
  using GetLevel = void (*)(GLenum, GLint, GLenum, GLint*);
  const auto isTexture = reinterpret_cast<IsTexture>(render::gl::glxProcAddress("glIsTexture"));
  const auto bindTexture = reinterpret_cast<BindTexture>(render::gl::glxProcAddress("glBindTexture"));
  const auto getLevel = reinterpret_cast<GetLevel>(render::gl::glxProcAddress("glGetTexLevelParameteriv"));
  for (const auto& image : images) {
    ASSERT_TRUE(isTexture(image.image));
    bindTexture(GL_TEXTURE_2D, image.image);
    GLint w = 0;
    getLevel(GL_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &w);
    EXPECT_EQ(w, 64);
  }
  EXPECT_EQ(g_appLookups, 0) << "the runtime's lookups went to the app's provider";
  XR_OK(xrDestroySwapchain(sc));
}

}  // namespace
}  // namespace fp
