#pragma once
// `tvf render KIND INPUT -o OUT…`: pictures and videos of a field as PNG frames and/or
// MP4. KIND is texture (render/texture_animation.h), painterly (render/painterly.h),
// crowd (render/crowd.h), particles (render/particles.h) or grass (render/grass.h). INPUT is a folder written by
// `tvf generate`, its field.tvff, or a scene (generated first).
#include <CLI/CLI.hpp>

#include <cmath>
#include <memory>
#include <optional>
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
  CLI::App* painterly_ = nullptr;
  CLI::App* crowd_ = nullptr;
  CLI::App* particles_ = nullptr;
  CLI::App* grass_ = nullptr;
  int run_texture();
  int run_painterly();
  int run_crowd();
  int run_particles();
  int run_grass();
  int frames_or_default() const;
  std::string input_;
  std::vector<std::string> outputs_;
  int size_ = 1024;
  double fps_ = 25;
  std::optional<int> frames_;  // not given: the field's frames
  double time_scale_ = 1;      // particles, painterly
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
  std::vector<double> view_, up_;  // surfaces
  std::vector<std::string> streaklines_;  // dye seeds: X,Y (planar) or X,Y,Z (surfaces)
  std::vector<std::string> timelines_;    // --timeline segments
  double fov_ = 30, spacing_ = 1.0;
  // painterly
  std::string image_, mask_;
  double stroke_width_ = 6, stroke_length_ = 24, density_ = 2;
  // crowd
  std::string crowd_file_, csv_;
  std::optional<double> weight_goal_, weight_field_;
  // particles
  int count_ = 2000;
  int app_size_ = 800;  // crowd and particles: pixels on the long side
  double particle_size_ = 10, spin_ = std::nan("");
  // grass
  int grass_count_ = 32000, grass_segments_ = 4, grass_size_ = 960;
  double grass_length_ = 0.035, grass_bend_ = 75, grass_wind_ = 0, grass_response_ = 1, grass_elevation_ = 50;
};

}  // namespace tvf::cli
