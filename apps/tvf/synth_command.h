#pragma once
// `tvf render synth|terrain INPUT -o OUT…`: exemplar-based texture synthesis guided by a
// field (synth/planar_synthesis.h, synth/surface_synthesis.h) and evolving terrain
// (synth/terrain.h). Registered on the `render` subcommand; kept apart from
// render_command.cpp so that each render kind stays one file.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace tvf::cli {

class SynthCommand {
public:
  // Adds `synth` and `terrain` to the `render` subcommand.
  explicit SynthCommand(CLI::App& render);
  bool selected() const { return synth_->parsed() || terrain_->parsed(); }
  // Throws tvf::Error on bad input.
  int run();

private:
  int run_checked();
  CLI::App* synth_ = nullptr;
  CLI::App* terrain_ = nullptr;
  std::string input_, exemplar_, meshes_, mesh_format_;
  std::vector<std::string> outputs_;
  std::vector<double> view_, up_;  // surfaces: the camera
  CLI::Option* height_scale_option_ = nullptr;
  int size_ = 512, frames_ = kFramesNotGiven, exemplar_size_ = 64;
  static constexpr int kFramesNotGiven = -2147483647;  // --frames left out: the field's frames
  int levels_ = 3, frame_levels_ = 2, neighbourhood_ = 7, iterations_ = 2, iterations_first_ = 5, stride_ = 2;
  int mesh_resolution_ = 128, renew_frames_ = 8, density_ = 0;
  double fps_ = 25, temporal_weight_ = 0.6, max_distortion_ = 1.6, speed_ = 0, texel_ = 0, height_scale_ = 0, relief_ = 0;
  unsigned long long seed_ = 1;
  bool quiet_ = false;
};

}  // namespace tvf::cli
