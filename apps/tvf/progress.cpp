#include "progress.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <unistd.h>

namespace tvf::cli {

bool progress_wanted() {
  const char* env = std::getenv("TVF_PROGRESS");
  if (env && std::strcmp(env, "0") == 0) return false;
  if (env && std::strcmp(env, "1") == 0) return true;
  return ::isatty(STDERR_FILENO) != 0;
}

Progress::Progress(std::string label, bool enabled) : label_(std::move(label)), enabled_(enabled) {}

Progress::~Progress() { finish(); }

void Progress::update(int done, int total) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  std::fprintf(stderr, "\r\033[K%s: %d/%d frames", label_.c_str(), done, total);
  std::fflush(stderr);
  open_ = true;
}

void Progress::note(const std::string& what) {
  if (!enabled_) return;
  std::fprintf(stderr, "\r\033[K%s: %s", label_.c_str(), what.c_str());
  std::fflush(stderr);
  open_ = true;
}

void Progress::finish() {
  if (enabled_ && open_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  open_ = false;
}

}  // namespace tvf::cli
