#pragma once
/// What a window writes of its frames: PNG frames (F9, --record-dir) and the video (F8, ffmpeg) of the 3D
/// view, screenshots with the panel on them (F12), and the --screenshot of the last frame. It reads back the
/// bound default framebuffer; the panel's state says what is on.

#include <memory>
#include <optional>
#include <string>

#include "engine/cli.h"
#include "engine/panel.h"

namespace fp::render {
class VideoWriter;
struct Image;
}  // namespace fp::render

namespace fp::engine {

/// The frame writers of one window.
class FrameCapture {
 public:
  /// `options`: --screenshot and --record-dir (which turns frame recording on in `panel`); `frames`: the
  /// --frames limit, whose last frame is the screenshot's
  FrameCapture(const CliOptions& options, std::optional<int> frames, PanelState& panel);
  ~FrameCapture();
  FrameCapture(const FrameCapture&) = delete;
  FrameCapture& operator=(const FrameCapture&) = delete;

  /// after the 3D view, before the panel: the PNG frame and the video frame of a `width` x `height` [px]
  /// framebuffer; `frameRate` [1/s] is the video's
  void sceneDrawn(PanelState& panel, int width, int height, double frameRate);
  /// after the panel, before the swap: the F12 screenshot and, at frame `frame`, the --screenshot
  void frameDrawn(PanelState& panel, int frame, int width, int height);
  /// writes the --screenshot if it was not written yet (a window closed before --frames)
  void finish();

 private:
  std::string m_screenshotPath;
  std::optional<int> m_frames;
  std::unique_ptr<render::Image> m_lastImage;
  bool m_screenshotWritten = false;
  std::string m_recordDir;
  int m_recorded = 0;
  std::unique_ptr<render::VideoWriter> m_video;
  int m_videoSize[2] = {0, 0};
  int m_videos = 0;
  int m_screenshots = 0;
};

}  // namespace fp::engine
