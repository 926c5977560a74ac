#pragma once
// Progress on a terminal, silence in pipelines: a single self-rewriting line on stderr
// when stderr is a TTY, nothing otherwise.
#include <chrono>
#include <string>

namespace tvf::cli {

class Progress {
public:
  Progress(std::string label, bool enabled);
  ~Progress();
  void update(int done, int total);
  void note(const std::string& what);  // a step without a count
  void finish();

private:
  std::string label_;
  bool enabled_;
  bool open_ = false;
  std::chrono::steady_clock::time_point last_{};
};

// True when stderr is a terminal (and TVF_PROGRESS is not "0").
bool progress_wanted();

}  // namespace tvf::cli
