#include "common/video_writer.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "common/process.h"

namespace graspbed::image {
namespace {

constexpr const char* kInstallHint = "on Debian: apt-get install ffmpeg";
// Last bytes of ffmpeg's stderr quoted in errors.
constexpr size_t kErrorTailBytes = 600;

std::string UniqueSuffix() {
  static std::atomic<uint64_t> counter{0};
  return ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

bool IsExecutableFile(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

std::string ReadTail(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  std::string all = text.str();
  while (!all.empty() && (all.back() == '\n' || all.back() == ' ')) all.pop_back();
  return all.size() > kErrorTailBytes ? "..." + all.substr(all.size() - kErrorTailBytes) : all;
}

/// Waits for `pid`; true when it exited with status 0.
bool WaitSucceeded(int pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return false;
  }
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

std::string RequireFfmpeg(const std::string& name) {
  const std::string path = FindProgram(name);
  if (path.empty()) {
    throw std::runtime_error("video: the ffmpeg program ('" + name + "') is not installed or not on PATH (" +
                             kInstallHint + ")");
  }
  return path;
}

}  // namespace

std::string FindProgram(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return IsExecutableFile(name) ? name : "";
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (IsExecutableFile(candidate)) return candidate;
  }
  return "";
}

VideoWriter::VideoWriter(const Options& options) : options_(options) {
  if (options.width_px <= 0 || options.height_px <= 0 || options.width_px % 2 != 0 ||
      options.height_px % 2 != 0) {
    throw std::invalid_argument("video size " + std::to_string(options.width_px) + "x" +
                                std::to_string(options.height_px) +
                                ": width and height must be even and > 0 (H.264)");
  }
  if (!(options.fps > 0.0 && options.fps <= 1000.0)) {
    throw std::invalid_argument("video frame rate " + std::to_string(options.fps) +
                                ": must be in (0, 1000] fps");
  }
  const std::string ffmpeg = RequireFfmpeg(options.ffmpeg);
  temp_path_ = options.path + UniqueSuffix();
  log_path_ = temp_path_ + ".log";
  int fds[2];
  // Close-on-exec: another encoder started in parallel (a suite) must not hold this pipe open, or
  // this ffmpeg would never see the end of its input.
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw std::runtime_error(std::string("video: pipe: ") + std::strerror(errno));
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%.6g", options.fps);
  const std::vector<std::string> argv = {
      ffmpeg,       "-nostdin",  "-hide_banner",
      "-loglevel",  "error",     "-y",
      "-f",         "rawvideo",  "-pix_fmt",
      "rgb24",      "-s",        std::to_string(options.width_px) + "x" + std::to_string(options.height_px),
      "-framerate", rate,        "-i",
      "pipe:0",     "-an",       "-c:v",
      "libx264",    "-preset",   "veryfast",
      "-crf",       "23",        "-pix_fmt",
      "yuv420p",    "-movflags", "+faststart",
      "-f",         "mp4",       temp_path_};
  // -nostdin only stops ffmpeg reading keys from stdin; the frames still come in as pipe:0.
  try {
    pid_ = common::SpawnProcess(argv, fds[0], "", log_path_);
  } catch (...) {
    ::close(fds[0]);
    ::close(fds[1]);
    std::remove(log_path_.c_str());
    throw;
  }
  ::close(fds[0]);
  pipe_fd_ = fds[1];
}

VideoWriter::~VideoWriter() {
  Stop();
  std::remove(temp_path_.c_str());
  std::remove(log_path_.c_str());
}

void VideoWriter::Stop() {
  if (pipe_fd_ >= 0) {
    ::close(pipe_fd_);
    pipe_fd_ = -1;
  }
  if (pid_ > 0) {
    WaitSucceeded(pid_);
    pid_ = -1;
  }
}

std::string VideoWriter::ErrorText() const {
  const std::string tail = ReadTail(log_path_);
  return tail.empty() ? "no message" : tail;
}

void VideoWriter::Write(const RgbImage& frame) {
  if (frame.width_px != options_.width_px || frame.height_px != options_.height_px ||
      frame.rgb.size() != static_cast<size_t>(frame.width_px) * frame.height_px * 3) {
    throw std::invalid_argument("video: a " + std::to_string(frame.width_px) + "x" +
                                std::to_string(frame.height_px) + " frame for a " +
                                std::to_string(options_.width_px) + "x" + std::to_string(options_.height_px) +
                                " video");
  }
  if (pipe_fd_ < 0) throw std::runtime_error("video " + options_.path + ": already finished");
  // A dead ffmpeg makes write() raise SIGPIPE, which would end the whole program: blocked on this
  // thread while writing, and a pending one taken back afterwards.
  sigset_t pipe_signal;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  sigset_t previous;
  pthread_sigmask(SIG_BLOCK, &pipe_signal, &previous);
  const uint8_t* data = frame.rgb.data();
  size_t left = frame.rgb.size();
  int error = 0;
  while (left > 0) {
    const ssize_t written = ::write(pipe_fd_, data, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      error = errno;
      break;
    }
    data += written;
    left -= static_cast<size_t>(written);
  }
  if (error == EPIPE) {
    const timespec no_wait{};
    sigtimedwait(&pipe_signal, nullptr, &no_wait);
  }
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (error != 0) {
    Stop();
    throw std::runtime_error("video " + options_.path + ": ffmpeg stopped taking frames (" +
                             std::strerror(error) + "): " + ErrorText());
  }
  ++frames_;
}

void VideoWriter::Finish() {
  if (pipe_fd_ < 0 && pid_ < 0) throw std::runtime_error("video " + options_.path + ": already finished");
  ::close(pipe_fd_);
  pipe_fd_ = -1;
  const bool succeeded = WaitSucceeded(pid_);
  pid_ = -1;
  if (!succeeded) throw std::runtime_error("video " + options_.path + ": ffmpeg failed: " + ErrorText());
  if (std::rename(temp_path_.c_str(), options_.path.c_str()) != 0) {
    throw std::runtime_error("video " + options_.path + ": cannot rename the temporary file into place");
  }
}

void WriteVideoStrip(const std::string& video_path, int video_frames, int count, int columns,
                     int tile_width_px, const std::string& png_path, const std::string& ffmpeg) {
  if (count < 1 || video_frames < 1 || columns < 1 || tile_width_px < 0 || tile_width_px == 1) {
    throw std::invalid_argument("video strip: " + std::to_string(count) + " tiles of " +
                                std::to_string(video_frames) + " frames in rows of " +
                                std::to_string(columns) + ", " + std::to_string(tile_width_px) + " px wide");
  }
  count = std::min(count, video_frames);
  columns = std::min(columns, count);
  const int rows = (count + columns - 1) / columns;
  // Frames 0, step, 2 step, ...: the first and (about) the last of the video.
  const int step = count > 1 ? std::max(1, (video_frames - 1) / (count - 1)) : video_frames;
  const std::string scale = tile_width_px > 0 ? "scale=" + std::to_string(tile_width_px) + ":-2," : "";
  const std::string filter = "select='not(mod(n\\," + std::to_string(step) + "))'," + scale +
                             "tile=" + std::to_string(columns) + "x" + std::to_string(rows);
  const std::string temp = png_path + UniqueSuffix();
  const std::string log = temp + ".log";
  const std::vector<std::string> argv = {RequireFfmpeg(ffmpeg),
                                         "-nostdin",
                                         "-hide_banner",
                                         "-loglevel",
                                         "error",
                                         "-y",
                                         "-i",
                                         video_path,
                                         "-vf",
                                         filter,
                                         "-frames:v",
                                         "1",
                                         "-update",
                                         "1",
                                         "-f",
                                         "image2",
                                         "-c:v",
                                         "png",
                                         temp};
  const int pid = common::SpawnProcess(argv, -1, "", log);
  const bool succeeded = WaitSucceeded(pid);
  const std::string message = ReadTail(log);
  std::remove(log.c_str());
  if (!succeeded || std::rename(temp.c_str(), png_path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw std::runtime_error("video strip " + png_path +
                             ": ffmpeg failed: " + (message.empty() ? "no message" : message));
  }
}

}  // namespace graspbed::image
