#include "tvf/render/video.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace tvf {

namespace fs = std::filesystem;

bool ffmpeg_available() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':'))
    if (!dir.empty() && ::access((fs::path(dir) / "ffmpeg").c_str(), X_OK) == 0) return true;
  return false;
}

namespace {

// The last non-empty line of ffmpeg's log, for error messages.
std::string last_line(const std::string& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

// Blocks SIGPIPE in this thread while writing to ffmpeg, so a dead ffmpeg gives EPIPE
// (reported as an error) instead of killing the process; a SIGPIPE left pending by the
// writes is consumed before the mask is restored.
class SigpipeGuard {
public:
  SigpipeGuard() {
    sigemptyset(&pipe_);
    sigaddset(&pipe_, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_, &old_);
  }
  ~SigpipeGuard() {
    const timespec zero{0, 0};
    while (sigtimedwait(&pipe_, nullptr, &zero) > 0) {
    }
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }

private:
  sigset_t pipe_, old_;
};

}  // namespace

VideoWriter::VideoWriter(std::string path, int width, int height, const VideoOptions& options)
    : path_(std::move(path)), width_(width), height_(height), gray_(options.gray) {
  TVF_CHECK(width > 0 && height > 0, "video {}×{}", width, height);
  if (!(options.fps > 0) || options.fps > 1000)
    throw_input_error(path_, "", fmt::format("the frame rate must be in (0, 1000], not {}", options.fps));
  if (!ffmpeg_available())
    throw_input_error(path_, "", "cannot write MP4 video: ffmpeg was not found (install the Debian package ffmpeg)");
  tmp_ = temporary_sibling(path_).string() + ".mp4";
  log_ = temporary_sibling(path_).string() + ".log";
  const std::string size = fmt::format("{}x{}", width, height);
  const std::string fps = fmt::format("{}", options.fps);
  const std::string crf = fmt::format("{}", options.crf);
  std::vector<std::string> args = {"ffmpeg", "-nostdin", "-hide_banner", "-loglevel", "error", "-y",
                                   "-f", "rawvideo", "-pix_fmt", gray_ ? "gray" : "rgb24", "-s", size, "-r", fps, "-i", "pipe:0"};
  // yuv420p needs even sizes: an odd one is padded by a pixel (no filter otherwise).
  if (width % 2 != 0 || height % 2 != 0) args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"});
  args.insert(args.end(), {"-c:v", "libx264", "-preset", options.preset, "-crf", crf, "-pix_fmt", "yuv420p",
                           "-movflags", "+faststart", "-f", "mp4", tmp_});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw_input_error(path_, "", "cannot start ffmpeg (no pipe)");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, "ffmpeg", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[0]);
  if (rc != 0) {
    ::close(fds[1]);
    std::error_code ec;
    fs::remove(log_, ec);
    throw_input_error(path_, "", fmt::format("cannot start ffmpeg ({})", std::strerror(rc)));
  }
  pid_ = pid;
  pipe_ = fds[1];
  // A pipe of 1 MiB where the system allows it (fewer switches between tvf and ffmpeg);
  // the default 64 KiB otherwise.
  (void)::fcntl(pipe_, F_SETPIPE_SZ, 1 << 20);
  buffer_.resize(static_cast<size_t>(width) * static_cast<size_t>(height) * (gray_ ? 1 : 3));
}

VideoWriter::~VideoWriter() { abort(); }

void VideoWriter::abort() {
  if (pipe_ >= 0) ::close(pipe_);
  pipe_ = -1;
  if (pid_ > 0) {
    ::kill(pid_, SIGTERM);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }
  std::error_code ec;
  if (!tmp_.empty()) fs::remove(tmp_, ec);
  if (!log_.empty()) fs::remove(log_, ec);
}

void VideoWriter::add(const Image& frame) {
  TVF_CHECK(frame.width == width_ && frame.height == height_, "frame {}×{} for a {}×{} video", frame.width,
            frame.height, width_, height_);
  TVF_CHECK(pipe_ >= 0, "frame added to a finished video");
  const std::uint32_t* pixels = frame.pixels.data();
  const size_t n = frame.pixels.size();
  unsigned char* out = buffer_.data();
  if (gray_) {
    std::uint32_t colour = 0;  // nonzero when some pixel's red, green and blue differ
    for (size_t k = 0; k < n; ++k) {
      const std::uint32_t p = pixels[k];
      colour |= (p ^ (p >> 8)) & 0xFFFFu;
      out[k] = static_cast<unsigned char>(p);
    }
    TVF_CHECK(colour == 0, "a coloured frame given to the gray video {}", path_);
  } else {
    for (size_t k = 0; k < n; ++k) {
      const std::uint32_t p = pixels[k];
      out[3 * k] = static_cast<unsigned char>(p >> 16);
      out[3 * k + 1] = static_cast<unsigned char>(p >> 8);
      out[3 * k + 2] = static_cast<unsigned char>(p);
    }
  }
  const SigpipeGuard guard;
  size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t written = ::write(pipe_, buffer_.data() + done, buffer_.size() - done);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) {
      const std::string why = last_line(log_);
      abort();
      throw_input_error(path_, "", fmt::format("ffmpeg stopped while encoding{}", why.empty() ? "" : " (" + why + ")"));
    }
    done += static_cast<size_t>(written);
  }
  ++frames_;
}

void VideoWriter::finish() {
  TVF_CHECK(pipe_ >= 0, "video finished twice");
  ::close(pipe_);
  pipe_ = -1;
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string why = last_line(log_);
    abort();
    throw_input_error(path_, "", fmt::format("ffmpeg could not encode the video{}", why.empty() ? "" : " (" + why + ")"));
  }
  std::error_code ec;
  fs::rename(tmp_, path_, ec);
  if (ec) {
    abort();
    throw_input_error(path_, "", fmt::format("cannot move the finished video into place ({})", ec.message()));
  }
  tmp_.clear();
  fs::remove(log_, ec);
  log_.clear();
}

}  // namespace tvf
