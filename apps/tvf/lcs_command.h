#pragma once
// The Lagrangian descriptors of a field (DESIGN §12): `tvf ftle` (finite-time Lyapunov
// exponents, integrate/ftle.h), `tvf streaklines` and `tvf timelines`
// (integrate/streakline.h). INPUT is a folder written by `tvf generate`, its field.tvff,
// or a scene (generated first), as `tvf analyze` takes it.
#include "tvf/render/texture_animation.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace tvf::cli {

class LcsCommand {
public:
  // Registers `ftle`, `streaklines` and `timelines` on `app`.
  explicit LcsCommand(CLI::App& app);
  bool selected() const { return ftle_->parsed() || streak_->parsed() || timeline_->parsed(); }
  // Runs the chosen subcommand; throws tvf::Error on bad input.
  int run();

private:
  int run_ftle();
  int run_streaklines();
  int run_timelines();
  // The surface pictures' camera from --view and --up (checked: three finite numbers, not
  // all zero); `given` says whether --view was.
  SurfaceView surface_view(bool& given) const;
  CLI::App* ftle_ = nullptr;
  CLI::App* streak_ = nullptr;
  CLI::App* timeline_ = nullptr;
  std::string input_, out_;
  bool quiet_ = false, no_picture_ = false, no_vtk_ = false;
  double dt_ = 0;
  int size_ = 800;
  std::vector<double> view_, up_;  // surfaces: the camera (empty: the default)
  // ftle
  double horizon_ = 0;
  std::string direction_ = "both", beyond_ = "clamp";
  int pictures_ = 4;
  int every_ = 1;
  bool compose_ = false;
  // streaklines and timelines
  std::vector<double> seed_, line_;
  std::vector<double> from_, to_;  // empty: the field's time range
  double spacing_ = 0, max_gap_ = 0;
  int element_ = -1;  // streaklines --element: a sketched streakline of the scene
  int count_ = 100;
};

}  // namespace tvf::cli
