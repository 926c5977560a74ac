#pragma once
// `tvf render texture INPUT -o OUT…`: texture animation of a field as PNG frames and/or
// MP4 (render/texture_animation.h). INPUT is a folder written by `tvf generate`, its
// field.tvff, or a scene (generated first).
#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

namespace tvf::cli {

class RenderCommand {
public:
  // Registers `render` (and its `texture` subcommand) on `app`.
  explicit RenderCommand(CLI::App& app);
  bool selected() const { return render_->parsed(); }
  // Runs the chosen subcommand; throws tvf::Error on bad input.
  int run();

private:
  CLI::App* render_ = nullptr;
  CLI::App* texture_ = nullptr;
  std::string input_;
  std::vector<std::string> outputs_;
  int size_ = 1024;
  double fps_ = 25;
  int frames_ = 0;
  std::string range_;
  std::vector<std::string> overlay_;
  double alpha_ = 0.1;
  int lic_ = -1;
  double noise_scale_ = 0;
  double speed_ = 0;
  double contrast_ = 1;
  unsigned long long seed_ = 1;
  bool quiet_ = false;
  bool physical_ = false;
};

}  // namespace tvf::cli
