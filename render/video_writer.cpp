#include "render/video_writer.h"

#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "render/render_error.h"

extern char** environ;

namespace fp::render {

std::string VideoWriter::findFfmpeg() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = end > start ? dirs.substr(start, end - start) : ".";
    const std::string candidate = dir + "/ffmpeg";
    struct stat st;
    if (::stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(candidate.c_str(), X_OK) == 0)
      return candidate;
    start = end + 1;
  }
  return "";
}

VideoWriter::VideoWriter(const std::string& path, int width, int height, double fps)
    : m_path(path), m_width(width), m_height(height) {
  if (width < 2 || height < 2 || !(fps > 0.0))
    throw RenderError("video " + path + ": bad size or frame rate");
  const std::string ffmpeg = findFfmpeg();
  if (ffmpeg.empty())
    throw RenderError("cannot write video " + path +
                      ": the ffmpeg program is not on PATH (apt install ffmpeg)");
  char size[32], rate[32];
  std::snprintf(size, sizeof(size), "%dx%d", width, height);
  std::snprintf(rate, sizeof(rate), "%.6g", fps);
  const std::vector<std::string> args = {ffmpeg, "-hide_banner", "-loglevel", "error", "-nostdin", "-y", "-f",
                                         "rawvideo", "-pix_fmt", "rgba", "-s", size, "-r", rate, "-i",
                                         "pipe:0",
                                         // even sizes for yuv420p
                                         "-vf", "crop=trunc(iw/2)*2:trunc(ih/2)*2", "-c:v", "libx264",
                                         "-preset", "veryfast", "-crf", "18", "-pix_fmt", "yuv420p", path};
  std::vector<char*> argv;
  for (const std::string& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);

  int fds[2];
  if (::pipe(fds) != 0)
    throw RenderError("cannot write video " + path + ": " + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  const int rc = posix_spawn(&m_pid, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[0]);
  if (rc != 0) {
    ::close(fds[1]);
    throw RenderError("cannot write video " + path + ": cannot start " + ffmpeg + ": " + std::strerror(rc));
  }
  m_pipe = fds[1];
}

VideoWriter::~VideoWriter() {
  try {
    close();
  } catch (const RenderError& e) {
    std::fprintf(stderr, "%s\n", e.what());
  }
}

void VideoWriter::write(const Image& frame) {
  if (m_pipe < 0)
    throw RenderError("video " + m_path + ": already closed");
  if (frame.width != m_width || frame.height != m_height)
    throw RenderError("video " + m_path + ": frame size differs from the video's");
  // a stopped ffmpeg must give an error here, not a SIGPIPE that ends the program
  sigset_t pipeSignal, previous;
  sigemptyset(&pipeSignal);
  sigaddset(&pipeSignal, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipeSignal, &previous);
  const std::uint8_t* data = frame.rgba.data();
  std::size_t left = frame.rgba.size();
  int error = 0;
  while (left > 0) {
    const ssize_t n = ::write(m_pipe, data, left);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      error = errno;
      break;
    }
    data += n;
    left -= std::size_t(n);
  }
  if (error == EPIPE) {
    const timespec zero{0, 0};
    sigtimedwait(&pipeSignal, nullptr, &zero);  // drop the pending SIGPIPE
  }
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (error)
    throw RenderError("video " + m_path + ": ffmpeg stopped taking frames (" + std::strerror(error) + ")");
  ++m_frames;
}

void VideoWriter::close() {
  if (m_pipe < 0)
    return;
  ::close(m_pipe);
  m_pipe = -1;
  int status = 0;
  while (::waitpid(m_pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw RenderError("video " + m_path + ": ffmpeg failed (exit status " +
                      std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
}

}  // namespace fp::render
