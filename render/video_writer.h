#pragma once
/// Videos of rendered frames: raw RGBA frames piped into the `ffmpeg` program (Debian's ffmpeg), found on
/// PATH when the writer starts, encoded as H.264 (yuv420p, so every player opens it) at the scene's frame
/// rate. Nothing links against FFmpeg's libraries.

#include <sys/types.h>
#include <string>

#include "render/image.h"

namespace fp::render {

/// One video file being written. Frames must all have the size given at construction.
class VideoWriter {
 public:
  /// Starts `ffmpeg` writing `path` (the container from its extension, e.g. .mp4) from width x height frames
  /// [px] (odd sizes lose their last row or column) at `fps` frames a second (> 0). Throws RenderError with
  /// one line when ffmpeg is not on PATH or cannot be started.
  VideoWriter(const std::string& path, int width, int height, double fps);
  /// Finishes the file (close()), swallowing its error.
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  /// Appends one frame (rows from the top, as readFramebuffer gives them). Throws RenderError when the size
  /// differs or ffmpeg has stopped.
  void write(const Image& frame);
  /// Ends the stream and waits for ffmpeg; throws RenderError when it failed. Idempotent.
  void close();

  /// frames written so far
  int framesWritten() const { return m_frames; }
  /// the output file
  const std::string& path() const { return m_path; }

  /// the full path of the `ffmpeg` program on PATH, or "" when there is none
  static std::string findFfmpeg();

 private:
  std::string m_path;
  int m_width = 0;
  int m_height = 0;
  int m_frames = 0;
  int m_pipe = -1;  // write end of ffmpeg's stdin
  pid_t m_pid = -1;
};

}  // namespace fp::render
