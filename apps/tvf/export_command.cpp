#include "export_command.h"

#include "progress.h"

#include "tvf/api/design.h"
#include "tvf/field/animation_export.h"

#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace tvf::cli {

CLI::App* add_export_command(CLI::App& app, ExportArgs& args) {
  auto* cmd = app.add_subcommand(
      "export", "Write a field for animation tools: OpenVDB velocity grids (planar) or PLY with vx, vy, vz per frame");
  cmd->add_option("input", args.input, "Folder written by `tvf generate` (or its field.tvff), or a scene file")
      ->required();
  cmd->add_option("-o,--output", args.out, "Output folder (created if missing)")->required();
  auto* vdb = cmd->add_flag("--vdb", args.vdb, "DIR/velocity_NNNN.vdb: one Vec3f grid `v` per frame (planar grids)");
  auto* ply = cmd->add_flag("--ply", args.ply, "DIR/velocity_NNNN.ply: the mesh with per-vertex vx, vy, vz per frame");
  vdb->excludes(ply);
  cmd->add_flag("-q,--quiet", args.quiet, "Print nothing but errors and warnings");
  return cmd;
}

int run_export(const ExportArgs& args) {
  Progress progress("tvf export", !args.quiet && progress_wanted());
  Design design = Design::open(args.input);
  GenerateOptions options;
  options.progress = [&](int done, int total) { progress.update(done, total); };
  options.stage = [&](const std::string& what) { progress.note(what); };
  if (!design.has_field()) progress.note("generating");
  const Field& field = design.generate(options);
  const TangentBundle& bundle = design.field_space()->bundle();
  const bool vdb = args.vdb || (!args.ply && design.field_space()->planar());
  progress.note(vdb ? "writing VDB files" : "writing PLY files");
  const auto files = vdb ? write_vdb_sequence(args.out, bundle, field, args.input)
                         : write_ply_sequence(args.out, bundle, field);
  progress.finish();
  for (const auto& w : design.report().warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!args.quiet)
    std::printf("wrote %zu %s files (one per frame) to %s\n", files.size(), vdb ? "OpenVDB" : "PLY",
                fs::absolute(args.out).lexically_normal().c_str());
  return 0;
}

}  // namespace tvf::cli
