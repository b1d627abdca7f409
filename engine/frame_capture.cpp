#include "engine/frame_capture.h"

#include <cstdio>
#include <filesystem>

#include "render/image.h"
#include "render/render_error.h"
#include "render/video_writer.h"

namespace fp::engine {

FrameCapture::FrameCapture(const CliOptions& options, std::optional<int> frames, PanelState& panel)
    : m_screenshotPath(options.screenshot), m_frames(frames), m_recordDir(options.recordDir) {
  panel.recordFrames = !m_recordDir.empty();
  if (m_recordDir.empty())
    m_recordDir = "frames";
}

FrameCapture::~FrameCapture() = default;

void FrameCapture::sceneDrawn(PanelState& panel, int width, int height, double frameRate) {
  std::error_code ec;
  if (panel.recordFrames && width > 0) {
    std::filesystem::create_directories(m_recordDir, ec);
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", m_recorded++);
    render::writePng((std::filesystem::path(m_recordDir) / name).string(),
                     render::readFramebuffer(0, 0, 0, width, height));
  }
  if (panel.recordVideo && width > 0) {
    try {
      if (m_video && (m_video->framesWritten() > 0 && (width != m_videoSize[0] || height != m_videoSize[1])))
        m_video.reset();  // a resized window starts a new file
      if (!m_video) {
        char name[32];
        std::snprintf(name, sizeof(name), "video_%03d.mp4", m_videos++);
        m_video = std::make_unique<render::VideoWriter>(name, width, height, frameRate);
        m_videoSize[0] = width;
        m_videoSize[1] = height;
        panel.message = std::string("recording video to ") + name + " (F8 stops)";
      }
      m_video->write(render::readFramebuffer(0, 0, 0, width, height));
    } catch (const render::RenderError& e) {
      panel.message = e.what();
      panel.recordVideo = false;
      m_video.reset();
    }
  } else if (m_video) {
    const std::string written = m_video->path();
    try {
      m_video->close();
      panel.message = "video written to " + written;
    } catch (const render::RenderError& e) {
      panel.message = e.what();
    }
    m_video.reset();
  }
}

void FrameCapture::frameDrawn(PanelState& panel, int frame, int width, int height) {
  if (panel.screenshot && width > 0) {
    panel.screenshot = false;
    char name[40];
    std::snprintf(name, sizeof(name), "screenshot_%03d.png", m_screenshots++);
    render::writePng(name, render::readFramebuffer(0, 0, 0, width, height));
    panel.message = std::string("screenshot written to ") + name;
  }
  if (!m_screenshotPath.empty() && width > 0) {
    const bool last = m_frames && frame == *m_frames - 1;
    if (last || !m_frames) {
      // without --frames any frame may be the last: keep it, write it when the window closes
      m_lastImage = std::make_unique<render::Image>(render::readFramebuffer(0, 0, 0, width, height));
      if (last)
        finish();
    }
  }
}

void FrameCapture::finish() {
  if (m_screenshotWritten || m_screenshotPath.empty() || !m_lastImage)
    return;
  const std::filesystem::path parent = std::filesystem::path(m_screenshotPath).parent_path();
  std::error_code ec;
  if (!parent.empty())
    std::filesystem::create_directories(parent, ec);
  render::writePng(m_screenshotPath, *m_lastImage);
  m_screenshotWritten = true;
}

}  // namespace fp::engine
