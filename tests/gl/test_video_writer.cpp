// The video writer (label gl, beside the image tests): a few frames through the ffmpeg program, checked
// with ffprobe when it is there; a one-line error when ffmpeg is not on PATH. The window's record toggle
// (F8, the panel's "record video": engine::FrameCapture) on an OSMesa framebuffer.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "engine/frame_capture.h"
#include "engine/panel.h"
#include "render/gl_api.h"
#include "render/offscreen_context.h"
#include "render/render_error.h"
#include "render/video_writer.h"

using namespace fp;
namespace fs = std::filesystem;

namespace {

render::Image gradient(int width, int height, int frame) {
  render::Image image;
  image.width = width;
  image.height = height;
  image.rgba.resize(std::size_t(width) * height * 4);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = &image.rgba[(std::size_t(y) * width + x) * 4];
      p[0] = std::uint8_t(4 * x + 20 * frame);
      p[1] = std::uint8_t(4 * y);
      p[2] = 128;
      p[3] = 255;
    }
  }
  return image;
}

std::string run(const std::string& command) {
  std::string out;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof(buffer), pipe))
      out += buffer;
    pclose(pipe);
  }
  return out;
}

/// ffprobe's "width,height,rate,frames" of the first video stream of `file`; nullopt without ffprobe
std::optional<std::string> probeVideo(const fs::path& file) {
  if (run("command -v ffprobe").empty())
    return std::nullopt;
  return run(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=nb_read_frames,width,height,r_frame_rate -of csv=p=0 '" +
      file.string() + "'");
}

/// Runs the test in `dir` (the window writes video_NNN.mp4 into the working directory) and goes back.
class InDirectory {
 public:
  explicit InDirectory(const fs::path& dir) : m_saved(fs::current_path()) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    fs::current_path(dir);
  }
  ~InDirectory() { fs::current_path(m_saved); }
  InDirectory(const InDirectory&) = delete;
  InDirectory& operator=(const InDirectory&) = delete;

 private:
  fs::path m_saved;
};

/// `frames` frames of the window's view through its record toggle, then the toggle off; the panel's message
std::string recordInWindow(engine::PanelState& panel, int frames) {
  render::OffscreenContext context(64, 48);
  engine::FrameCapture capture(engine::CliOptions(), std::nullopt, panel);
  panel.recordVideo = true;  // F8 or the panel's "record video"
  for (int f = 0; f < frames; ++f) {
    glClearColor(0.1f * float(f), 0.5f, 0.2f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    capture.sceneDrawn(panel, 64, 48, 30.0);
  }
  const bool recording = panel.recordVideo;
  panel.recordVideo = false;
  capture.sceneDrawn(panel, 64, 48, 30.0);
  return (recording ? "" : "stopped: ") + panel.message;
}

}  // namespace

TEST(VideoWriterTest, WritesAReadableVideoOfTheFrames) {
  if (render::VideoWriter::findFfmpeg().empty())
    GTEST_SKIP() << "ffmpeg is not on PATH: no video to write";
  const fs::path file = fs::path(::testing::TempDir()) / "fp_video_test.mp4";
  fs::remove(file);
  {
    render::VideoWriter video(file.string(), 64, 48, 60.0);
    for (int f = 0; f < 6; ++f)
      video.write(gradient(64, 48, f));
    EXPECT_EQ(video.framesWritten(), 6);
    video.close();
  }
  ASSERT_TRUE(fs::exists(file));
  EXPECT_GT(fs::file_size(file), 0u);
  const std::optional<std::string> probe = probeVideo(file);
  if (!probe)
    GTEST_SKIP() << "ffprobe is not on PATH: frame count and size not checked";
  EXPECT_NE(probe->find("64,48,60/1,6"), std::string::npos) << *probe;
}

TEST(VideoWriterTest, AFrameOfAnotherSizeIsAnError) {
  if (render::VideoWriter::findFfmpeg().empty())
    GTEST_SKIP() << "ffmpeg is not on PATH";
  const fs::path file = fs::path(::testing::TempDir()) / "fp_video_size.mp4";
  render::VideoWriter video(file.string(), 64, 48, 30.0);
  EXPECT_THROW(video.write(gradient(32, 48, 0)), render::RenderError);
}

TEST(VideoWriterTest, MissingFfmpegIsAOneLineError) {
  const char* path = std::getenv("PATH");
  const std::string saved = path ? path : "";
  const fs::path empty = fs::path(::testing::TempDir()) / "fp_empty_path";
  fs::create_directories(empty);
  setenv("PATH", empty.c_str(), 1);
  try {
    render::VideoWriter video((empty / "x.mp4").string(), 64, 48, 30.0);
    setenv("PATH", saved.c_str(), 1);
    FAIL() << "no error without ffmpeg";
  } catch (const render::RenderError& e) {
    setenv("PATH", saved.c_str(), 1);
    const std::string message = e.what();
    EXPECT_NE(message.find("ffmpeg"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(WindowVideoTest, TheRecordToggleWritesAVideoAtTheSceneFrameRate) {
  if (render::VideoWriter::findFfmpeg().empty())
    GTEST_SKIP() << "ffmpeg is not on PATH: no video to write";
  const fs::path dir = fs::path(::testing::TempDir()) / "fp_window_video";
  {
    const InDirectory in(dir);
    engine::PanelState panel;
    EXPECT_EQ(recordInWindow(panel, 5), "video written to video_000.mp4");
  }
  const fs::path file = dir / "video_000.mp4";
  ASSERT_TRUE(fs::exists(file));
  const std::optional<std::string> probe = probeVideo(file);
  if (!probe)
    GTEST_SKIP() << "ffprobe is not on PATH: frame count and size not checked";
  EXPECT_NE(probe->find("64,48,30/1,5"), std::string::npos) << *probe;
}

TEST(WindowVideoTest, TheRecordToggleWithoutFfmpegStopsWithAOneLineMessage) {
  const char* path = std::getenv("PATH");
  const std::string saved = path ? path : "";
  const fs::path dir = fs::path(::testing::TempDir()) / "fp_window_video_no_ffmpeg";
  std::string message;
  {
    const InDirectory in(dir);
    setenv("PATH", dir.c_str(), 1);
    engine::PanelState panel;
    message = recordInWindow(panel, 2);
    setenv("PATH", saved.c_str(), 1);
  }
  EXPECT_EQ(message.rfind("stopped: ", 0), 0u) << message;  // the toggle turned itself off
  EXPECT_NE(message.find("ffmpeg"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir / "video_000.mp4"));
}
