// The headset mode's mirror window (label xr, under Xvfb, core validation layer on): the window shows the
// left eye's image of the frame (read back from the runtime's swapchain and from the window) with the panel
// over it, and closing the window or Ctrl+C (SIGINT) ends the session in order (xrRequestExitSession,
// STOPPING, xrEndSession, EXITING, xrDestroyInstance) with exit code 0.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "render/image.h"
#include "tests/xr/xr_test_env.h"
// X11's atoms after everything else (its macros clash with Eigen)
#include <X11/Xatom.h>

namespace fp {
namespace {

using Clock = std::chrono::steady_clock;

std::string dirOf(const char* test) {
  return (std::filesystem::temp_directory_path() / "fp_xr_mirror_test" / test).string();
}

/// P6 image as written by the test runtime's capture, top row first
render::Image readPpm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int w = 0, h = 0, max = 0;
  in >> magic >> w >> h >> max;
  in.get();
  std::vector<unsigned char> rgb(std::size_t(w) * h * 3);
  in.read(reinterpret_cast<char*>(rgb.data()), std::streamsize(rgb.size()));
  render::Image image;
  if (!in)
    return image;
  image.width = w;
  image.height = h;
  image.rgba.resize(std::size_t(w) * h * 4);
  for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
    for (int c = 0; c < 3; ++c)
      image.rgba[i * 4 + c] = rgb[i * 3 + c];
    image.rgba[i * 4 + 3] = 255;
  }
  return image;
}

/// The app as a child process (stdout and stderr into `log`); returns its pid.
pid_t spawnApp(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    FILE* out = std::freopen(log.c_str(), "w", stdout);
    if (out)
      dup2(fileno(stdout), fileno(stderr));
    std::vector<char*> argv;
    static const std::string exe = FP_FLUIDPLAYING_EXE;
    argv.push_back(const_cast<char*>(exe.c_str()));
    for (const std::string& a : args)
      argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

/// waits up to `seconds` for the child; its exit code, or -1 (killed and reaped) when it did not end
int waitExit(pid_t pid, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  int status = 0;
  while (Clock::now() < end) {
    if (waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : -2;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

/// waits up to `seconds` until the runtime's statistics show `frames` submitted frames
bool waitSubmitted(const std::string& stats, long frames, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    if (test::runtimeStat(stats, "submitted") >= frames)
      return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

/// the top-level window of process `pid` (_NET_WM_PID), 0 when there is none
Window windowOf(Display* display, pid_t pid) {
  const Atom pidAtom = XInternAtom(display, "_NET_WM_PID", True);
  if (pidAtom == None)
    return 0;
  Window root = 0, parent = 0, *children = nullptr;
  unsigned count = 0;
  Window found = 0;
  if (!XQueryTree(display, DefaultRootWindow(display), &root, &parent, &children, &count))
    return 0;
  for (unsigned i = 0; i < count && !found; ++i) {
    Atom type = None;
    int format = 0;
    unsigned long items = 0, after = 0;
    unsigned char* data = nullptr;
    if (XGetWindowProperty(display, children[i], pidAtom, 0, 1, False, XA_CARDINAL, &type, &format, &items,
                           &after, &data) == Success &&
        data && items == 1 && format == 32 && pid_t(*reinterpret_cast<unsigned long*>(data)) == pid)
      found = children[i];
    if (data)
      XFree(data);
  }
  if (children)
    XFree(children);
  return found;
}

/// what a window manager sends when the user clicks the close button
void sendClose(Display* display, Window window) {
  XEvent e{};
  e.xclient.type = ClientMessage;
  e.xclient.window = window;
  e.xclient.message_type = XInternAtom(display, "WM_PROTOCOLS", False);
  e.xclient.format = 32;
  e.xclient.data.l[0] = long(XInternAtom(display, "WM_DELETE_WINDOW", False));
  e.xclient.data.l[1] = CurrentTime;
  XSendEvent(display, window, False, NoEventMask, &e);
  XFlush(display);
}

/// sets the runtime's environment for a run that goes on until it is ended from outside
std::string useRunningSession(const std::string& dir, const std::string& stats) {
  const std::string validation = test::useTestRuntime(dir);
  std::filesystem::remove(stats);
  setenv("FP_XR_STATS", stats.c_str(), 1);
  setenv("FP_XR_VIRTUAL_TIME", "1", 1);
  setenv("FP_XR_HEAD", "0,1.1,0,0", 1);
  setenv("FP_XR_SIZE", "64,48", 1);
  return validation;
}

TEST(XrMirror, ShowsTheLeftEyeWithThePanelOverIt) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Pixels");
  const std::string validation = test::useTestRuntime(dir);
  const std::string stats = dir + "/stats.txt", shot = dir + "/mirror.png";
  for (const std::string& f : {stats, shot, dir + "/eye0.ppm"})
    std::filesystem::remove(f);
  setenv("FP_XR_STATS", stats.c_str(), 1);
  setenv("FP_XR_VIRTUAL_TIME", "1", 1);
  setenv("FP_XR_HEAD", "0,1.1,0,0", 1);
  // the eyes as large as the window, so the mirror is the eye image pixel for pixel; the runtime ends the
  // session at frame 6, the one it captures, so the window's last image is that frame's left eye
  setenv("FP_XR_SIZE", "560,320", 1);
  setenv("FP_XR_EVENTS", "6:exit", 1);
  setenv("FP_XR_CAPTURE", ("6," + dir).c_str(), 1);
  const pid_t pid = spawnApp({"--xr", "--scene", FP_SOURCE_DIR "/assets/scenes/tiny_dam_break.json",
                              "--width", "560", "--height", "320", "--screenshot", shot},
                             dir + "/log.txt");
  EXPECT_EQ(waitExit(pid, 60.0), 0) << test::validationMessages(dir + "/log.txt");
  EXPECT_EQ(test::runtimeStat(stats, "ended"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "instances_destroyed"), 1);
  EXPECT_EQ(test::validationMessages(validation), "");
  const render::Image eye = readPpm(dir + "/eye0.ppm");
  ASSERT_EQ(eye.width, 560);
  ASSERT_EQ(eye.height, 320);
  ASSERT_TRUE(std::filesystem::exists(shot)) << test::validationMessages(dir + "/log.txt");
  const render::Image mirror = render::readPng(shot);
  ASSERT_EQ(mirror.width, 560);
  ASSERT_EQ(mirror.height, 320);
  // right of the panel (440 px wide at x = 8) the window is the eye's image, pixel for pixel
  long differ = 0, all = 0, lo = 255, hi = 0;
  for (int y = 0; y < 320; ++y) {
    for (int x = 460; x < 560; ++x, ++all) {
      bool same = true;
      for (int c = 0; c < 3; ++c) {
        same = same && std::abs(int(mirror.at(x, y)[c]) - int(eye.at(x, y)[c])) <= 1;
        lo = std::min<long>(lo, eye.at(x, y)[c]);
        hi = std::max<long>(hi, eye.at(x, y)[c]);
      }
      differ += !same;
    }
  }
  EXPECT_EQ(differ, 0) << "of " << all << " pixels";
  EXPECT_GT(hi - lo, 40) << "the eye shows the scene, not a flat colour";
  // where the panel is, the window is its dark background, and the eye image is not
  auto darkShare = [](const render::Image& image) {
    int dark = 0, n = 0;
    for (int y = 40; y < 300; y += 2) {
      for (int x = 20; x < 400; x += 2, ++n) {
        const std::uint8_t* c = image.at(x, y);
        dark += c[0] < 70 && c[1] < 70 && c[2] < 90;
      }
    }
    return double(dark) / n;
  };
  EXPECT_GT(darkShare(mirror), 0.4);
  EXPECT_LT(darkShare(eye), 0.2);
}

TEST(XrMirror, ClosingTheWindowEndsTheSessionInOrder) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Close"), stats = dir + "/stats.txt";
  const std::string validation = useRunningSession(dir, stats);
  Display* display = XOpenDisplay(nullptr);
  ASSERT_NE(display, nullptr);
  const pid_t pid =
      spawnApp({"--xr", "--quiet", "--scene", FP_SOURCE_DIR "/assets/scenes/tiny_dam_break.json", "--width",
                "320", "--height", "200"},
               dir + "/log.txt");
  ASSERT_TRUE(waitSubmitted(stats, 16, 60.0)) << test::validationMessages(dir + "/log.txt");
  const Window window = windowOf(display, pid);
  EXPECT_NE(window, 0u) << "no window of the app";
  if (window)
    sendClose(display, window);
  XCloseDisplay(display);
  EXPECT_EQ(waitExit(pid, 30.0), 0) << test::validationMessages(dir + "/log.txt");
  EXPECT_EQ(test::runtimeStat(stats, "begun"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "ended"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "instances_destroyed"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "submitted"), test::runtimeStat(stats, "waited"));
  EXPECT_EQ(test::validationMessages(validation), "");
}

TEST(XrMirror, InterruptEndsTheSessionInOrder) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Interrupt"), stats = dir + "/stats.txt";
  const std::string validation = useRunningSession(dir, stats);
  // without the mirror: the hidden context of the same window unit
  const pid_t pid = spawnApp(
      {"--xr", "--no-window", "--quiet", "--scene", FP_SOURCE_DIR "/assets/scenes/tiny_dam_break.json"},
      dir + "/log.txt");
  ASSERT_TRUE(waitSubmitted(stats, 16, 60.0)) << test::validationMessages(dir + "/log.txt");
  kill(pid, SIGINT);
  EXPECT_EQ(waitExit(pid, 30.0), 0) << test::validationMessages(dir + "/log.txt");
  EXPECT_EQ(test::runtimeStat(stats, "ended"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "instances_destroyed"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "submitted"), test::runtimeStat(stats, "waited"));
  EXPECT_EQ(test::validationMessages(validation), "");
}

TEST(XrMirror, FramesLimitEndsTheSessionInOrder) {
  if (!std::getenv("DISPLAY"))
    GTEST_SKIP() << "no display";
  const std::string dir = dirOf("Frames"), stats = dir + "/stats.txt";
  const std::string validation = useRunningSession(dir, stats);
  const pid_t pid = spawnApp({"--xr", "--quiet", "--frames", "12", "--width", "320", "--height", "200",
                              "--scene", FP_SOURCE_DIR "/assets/scenes/tiny_dam_break.json"},
                             dir + "/log.txt");
  EXPECT_EQ(waitExit(pid, 60.0), 0) << test::validationMessages(dir + "/log.txt");
  EXPECT_EQ(test::runtimeStat(stats, "ended"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "instances_destroyed"), 1);
  EXPECT_EQ(test::runtimeStat(stats, "submitted"), test::runtimeStat(stats, "waited"));
  EXPECT_EQ(test::validationMessages(validation), "");
}

}  // namespace
}  // namespace fp
