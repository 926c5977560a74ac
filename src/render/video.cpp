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
    : path_(std::move(path)), width_(width), height_(height) {
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
                                   "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", size, "-r", fps, "-i", "pipe:0"};
  // yuv420p needs even sizes: an odd one is padded by a pixel (no filter otherwise).
  if (width % 2 != 0 || height % 2 != 0) args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"});
  // x264's veryfast preset: half the encoder's CPU time of its fast preset, which it used
  // until issue 15, at the same file size and 0.8 dB less PSNR on 1024² texture
  // animations (docs/benchmarks.md, "Texture animation").
  args.insert(args.end(), {"-c:v", "libx264", "-preset", "veryfast", "-crf", crf, "-pix_fmt", "yuv420p",
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
  row_.resize(static_cast<size_t>(width) * 3);
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
  const SigpipeGuard guard;
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      const std::uint32_t p = frame.at(x, y);
      row_[3 * static_cast<size_t>(x)] = static_cast<unsigned char>(p >> 16);
      row_[3 * static_cast<size_t>(x) + 1] = static_cast<unsigned char>(p >> 8);
      row_[3 * static_cast<size_t>(x) + 2] = static_cast<unsigned char>(p);
    }
    size_t done = 0;
    while (done < row_.size()) {
      const ssize_t n = ::write(pipe_, row_.data() + done, row_.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const std::string why = last_line(log_);
        abort();
        throw_input_error(path_, "", fmt::format("ffmpeg stopped while encoding{}", why.empty() ? "" : " (" + why + ")"));
      }
      done += static_cast<size_t>(n);
    }
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
