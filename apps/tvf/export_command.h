#pragma once
// `tvf export DIR_OR_SCENE [--vdb | --ply] -o DIR`: the field for animation tools (DESIGN
// §12; field/animation_export.h): OpenVDB velocity grids per frame (planar grids,
// DIR/velocity_NNNN.vdb) or PLY meshes with per-vertex vx, vy, vz per frame (any domain,
// DIR/velocity_NNNN.ply). Without a flag: VDB on planar grids, PLY on surfaces.
#include <CLI/CLI.hpp>

#include <string>

namespace tvf::cli {

struct ExportArgs {
  std::string input;  // a scene file, or a folder written by `tvf generate` (or its field.tvff)
  std::string out;
  bool vdb = false;
  bool ply = false;
  bool quiet = false;
};

CLI::App* add_export_command(CLI::App& app, ExportArgs& args);
// Throws tvf::Error for bad input (a surface with --vdb, a build without OpenVDB).
int run_export(const ExportArgs& args);

}  // namespace tvf::cli
