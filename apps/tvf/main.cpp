// tvf: the command line. A thin client of libtvf: parse arguments, call the library,
// print results and errors (one sentence on stderr, non-zero exit).
#include "default_scene.h"
#include "design_check_output.h"
#include "edit_command.h"
#include "export_command.h"
#include "lcs_command.h"
#include "mpi_exec.h"
#include "progress.h"
#include "render_command.h"
#include "serve_command.h"
#include "synth_command.h"

#include "tvf/analysis/topology.h"
#include "tvf/api/design.h"
#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/design/design_check.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/design/outputs.h"
#include "tvf/scene/scene_json.h"
#include "tvf/render/plots.h"
#include "tvf/render/texture_animation.h"
#include "tvf/render/video.h"
#include "tvf/field/field_io.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/solve/distributed.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

namespace fs = std::filesystem;
using namespace tvf;

namespace {

struct GenerateArgs {
  std::string scene;
  std::string out;
  bool no_vtk = false;
  bool vtk_pieces = false;
  bool quiet = false;
};

int run_generate(Scene scene, const GenerateArgs& args, bool demo) {
  // Under mpirun every rank generates (the solve is shared); rank 0 alone reports and writes,
  // but for the VTK pieces that each rank writes when there are several.
  const bool root = distributed_rank() == 0;
  const bool show = root && !args.quiet && cli::progress_wanted();
  cli::Progress progress(demo ? "tvf demo" : "tvf generate", show);
  Design design(std::move(scene));
  progress.note("building the domain");
  const DesignSpace& space = design.space();
  if (space.repairs.changed() && !args.quiet && root)
    std::fprintf(stderr, "%s: repaired the mesh: removed %d duplicate faces and %d unreferenced vertices\n",
                 design.scene().resolved_mesh_path().c_str(), space.repairs.duplicate_faces_removed,
                 space.repairs.unreferenced_vertices_removed);

  GenerateOptions options;
  options.progress = [&](int done, int total) { progress.update(done, total); };
  options.stage = [&](const std::string& what) { progress.note(what); };
  const Field& field = design.generate(options);
  const GenerateReport& report = design.report();

  OutputOptions out_options;
  out_options.vtk = !args.no_vtk;
  out_options.vtk_pieces = args.vtk_pieces;
  out_options.on_step = [&](const std::string& what) { progress.note("writing " + what); };
  // With K > 1 ranks every rank writes its pieces of the VTK series (design/outputs.h).
  if (!root) {
    if (distributed_ranks() > 1) design.write_outputs(args.out, out_options);
    return 0;
  }
  auto files = design.write_outputs(args.out, out_options);
  // The demo ends with what the field is for: a texture animation of it (planar scenes).
  std::string demo_video;
  if (demo && space.planar()) {
    if (ffmpeg_available()) {
      TextureAnimationOptions video;
      video.texture.size = 512;
      video.overlay_singularities = true;
      video.video = (fs::path(args.out) / "demo.mp4").string();
      progress.note("rendering demo.mp4");
      video.progress = [&](int done, int total) { progress.update(done, total); };
      for (const auto& f : write_texture_animation(space.bundle(), field, video).files) files.push_back(f);
      demo_video = video.video;
    } else {
      std::fprintf(stderr, "note: ffmpeg is not installed, so the demo video was skipped "
                           "(scripts/install-deps.sh installs it)\n");
    }
  }
  progress.finish();

  for (const auto& w : report.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!args.quiet) {
    std::printf("generated %d frames × %d vertices by %s in %.2f s", report.frames, report.vertices,
                report.method.c_str(), report.seconds);
    if (report.residual > 0) std::printf(" (worst relative residual %.1e)", report.residual);
    std::printf("\n");
    for (const auto& e : report.edits) std::printf("  edit: %s\n", e.c_str());
    for (const auto& k : report.keyframe_intervals) {
      const auto bent = std::count_if(k.matched.begin(), k.matched.end(), [](const auto& m) { return m.detour > 0; });
      // A node matched across stability (a source-like one to a sink-like one).
      const auto repelling = [](SingularityType t) {
        return t == SingularityType::source || t == SingularityType::repelling_focus;
      };
      const auto attracting = [](SingularityType t) {
        return t == SingularityType::sink || t == SingularityType::attracting_focus;
      };
      const auto turning = std::count_if(k.matched.begin(), k.matched.end(), [&](const auto& m) {
        return (repelling(m.type) && attracting(m.to_type)) || (attracting(m.type) && repelling(m.to_type));
      });
      std::vector<std::string> notes;
      if (bent > 0)
        notes.push_back(fmt::format("{} bent{} to keep {:.3g} apart{}", bent, k.routing == "joint" ? " together" : "",
                                    k.separation,
                                    k.lowered_from > 0
                                        ? fmt::format(", the default {:.3g} lowered: no detour kept it", k.lowered_from)
                                        : std::string()));
      if (turning > 0) notes.push_back(fmt::format("{} changing stability through a center", turning));
      // Nodes the guide does not hold to their types (the warning above says which).
      const auto whole = std::count_if(k.matched.begin(), k.matched.end(), [](const auto& m) { return m.phase_turns != 0; });
      if (whole > 0) notes.push_back(fmt::format("{} turning a whole turn", whole));
      std::printf("  key frames %d → %d (t %g → %g): %zu matched%s, %zu pairs created and %zu cancelled at t = %g%s\n",
                  k.from_keyframe, k.to_keyframe, k.t0, k.t1, k.matched.size(),
                  notes.empty() ? "" : fmt::format(" ({})", fmt::join(notes, "; ")).c_str(),
                  k.created.size(), k.cancelled.size(), k.bifurcation_t,
                  k.unpaired_first.empty() && k.unpaired_second.empty()
                      ? ""
                      : fmt::format(", {} left unpaired", k.unpaired_first.size() + k.unpaired_second.size()).c_str());
      if (k.fallback)
        std::printf("    not guided, left free (key frames only): %s\n", k.unguided_reason.c_str());
    }
    if (const auto& inc = report.incompressible)
      std::printf("  incompressible (%s boundary): RMS divergence %.3g before, %.2g after (worst frame; "
                  "divergence.json has every frame)\n",
                  to_string(inc->boundary), inc->max_before, inc->max_after);
    std::printf("wrote %zu files to %s\n", files.size(), fs::absolute(args.out).lexically_normal().c_str());
    if (demo) {
      std::printf(
          "  field.npy       N×|V|×3 world vectors (numpy.load); vertices.npy, faces.npy, times.npy\n"
          "  field.pvd       the VTK time series: open it in ParaView (Glyph or Surface LIC)\n"
          "  field.tvff      the native field file (reloads exactly)\n"
          "  coherence.csv   temporal coherence per frame (paper Fig. 18)\n"
          "  scene.json      the scene that made it: edit it and run `tvf generate scene.json -o DIR`\n");
      if (!demo_video.empty())
        std::printf("  demo.mp4        the field as a texture animation, singularities coloured by type\n");
    }
  }
  return 0;
}

struct AnalyzeArgs {
  std::string input;  // a folder written by `tvf generate`, its field.tvff, or a scene file
  std::string out;
  bool quiet = false;
  bool no_plots = false;
};

// `tvf analyze DIR_OR_SCENE -o FILE.json`: the analysis JSON of DESIGN §9 for a generated
// folder (its field.tvff) or a scene (generated first).
int run_analyze(const AnalyzeArgs& args) {
  const bool show = !args.quiet && cli::progress_wanted();
  cli::Progress progress("tvf analyze", show);
  check_output_file(args.out);  // before the work, not after it
  // A folder written by `tvf generate` (or its field.tvff) is read; a scene is generated.
  Design design = Design::open(args.input);
  if (!design.has_field()) {
    progress.note("building the domain");
    design.space();
    GenerateOptions options;
    options.progress = [&](int done, int total) { progress.update(done, total); };
    options.stage = [&](const std::string& what) { progress.note(what); };
    design.generate(options);
  }
  const std::vector<std::string>& warnings = design.report().warnings;
  progress.note("analysing");
  const Topology& topology = design.analyze();
  const PeriodicOrbits& orbits = design.periodic_orbits();  // cycles and Hopf events (DESIGN §12)
  const int vertices = design.field().num_vertices();
  const Mesh& mesh = design.field_space()->mesh();
  // The field against its scene's design, when the scene is known.
  const std::optional<DesignCheck> check = design.check();
  progress.note("writing " + args.out);
  create_output_folder_for(args.out);
  write_file_atomically(args.out, design.analysis_json().dump() + "\n");
  if (check) write_file_atomically(cli::design_check_path(args.out), design_check_to_json(*check).dump(2) + "\n");
  // The pictures beside the JSON: STEM_coherence.{svg,png} and STEM_paths.{svg,png}.
  std::vector<std::string> pictures;
  if (!args.no_plots) {
    progress.note("drawing");
    const fs::path out(args.out);
    const std::string stem = (out.parent_path() / out.stem()).string();
    for (const auto& f : write_coherence_plot(stem + "_coherence", topology.times, topology.coherence))
      pictures.push_back(f);
    PlotOptions paths_plot;
    if (check) paths_plot.extra_paths = check->extra_paths;  // drawn dashed
    paths_plot.orbits = &orbits;
    for (const auto& f : write_paths_plot(stem + "_paths", mesh, topology, paths_plot)) pictures.push_back(f);
  }
  progress.finish();

  for (const auto& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!args.quiet) {
    size_t fewest = SIZE_MAX, most = 0;
    for (const auto& frame : topology.singularities) {
      fewest = std::min(fewest, frame.size());
      most = std::max(most, frame.size());
    }
    int creations = 0;
    for (const auto& b : topology.bifurcations) creations += b.kind == BifurcationKind::creation;
    std::printf("analysed %zu frames × %d vertices: %zu paths, %zu bifurcations (%d creations, %zu cancellations), "
                "%zu–%zu singularities per frame; wrote %s\n",
                topology.times.size(), vertices, topology.paths.size(), topology.bifurcations.size(), creations,
                topology.bifurcations.size() - static_cast<size_t>(creations), topology.times.empty() ? 0 : fewest,
                most, fs::absolute(args.out).lexically_normal().c_str());
    if (!orbits.orbits.empty()) {
      int tracks = 0;
      for (const auto& o : orbits.orbits) tracks = std::max(tracks, o.id + 1);
      std::printf("periodic orbits: %zu in %d tracks, %zu Hopf events\n", orbits.orbits.size(), tracks,
                  orbits.hopf.size());
    }
    for (const auto& f : pictures) std::printf("  %s\n", f.c_str());
    if (check) {
      std::printf("%s\n", check->summary().c_str());
      for (const auto& k : check->keyframe_intervals) {
        // Indices past the saddle–node bifurcations are Hopf events (design_check.h).
        const auto hopf = std::count_if(k.extra_bifurcations.begin(), k.extra_bifurcations.end(),
                                        [&](int i) { return i >= static_cast<int>(topology.bifurcations.size()); });
        std::printf("  key frames %d → %d (t %g → %g): %d bifurcations planned, %zu not asked for%s\n", k.from_keyframe,
                    k.to_keyframe, k.t0, k.t1, k.planned, k.extra_bifurcations.size(),
                    hopf ? fmt::format(" ({} Hopf)", hopf).c_str() : "");
        if (k.fallback) std::printf("    not guided, left free (key frames only): %s\n", k.unguided_reason.c_str());
      }
      std::printf("  %s\n", cli::design_check_path(args.out).c_str());
    } else
      std::printf("no scene.json beside the field: nothing to check the design against\n");
  }
  return 0;
}

int run_validate(const std::string& path, bool with_domain) {
  const Scene scene = load_scene(path);
  // With the domain, what only it tells too (points far off a surface, a sketched
  // streakline that meets itself on it), before the scene is called valid.
  std::optional<Design> design;
  if (with_domain) {
    design.emplace(scene);
    check_scene_on_domain(design->space(), scene);
  }
  std::printf("%s: valid tvf scene: %zu elements, %zu key frames, %d frames on [%g, %g], %s generator\n",
              path.c_str(), scene.elements.size(), scene.keyframes.size(), scene.time.frames,
              scene.time.t0, scene.time.t1, to_string(scene.generator));
  if (design) {
    const Mesh& mesh = design->space().mesh();
    std::printf("domain: %d vertices, %d faces, %s, Euler characteristic %d\n", mesh.num_vertices(),
                mesh.num_faces(), mesh.is_closed() ? "closed" : "with boundary", mesh.euler_characteristic());
  }
  for (const auto& w : design_warnings(scene)) std::fprintf(stderr, "warning: %s\n", w.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cli::run_mpi_program_if_launched(argv);  // under mpirun: tvf-mpi in this process's place (mpi_exec.h)
  const DistributedSession mpi;  // MPI and PETSc, where launched by mpirun (solve/distributed.h)
  CLI::App app{"tvf: design of time-varying vector fields on planar domains and surfaces.\n"
               "Run with no command to generate the built-in demo scene."};
  app.require_subcommand(0, 1);
  std::string demo_out = "tvf-out";
  bool demo_quiet = false;
  app.add_option("-o,--output", demo_out, "Output folder for the demo (no command given)");
  app.add_flag("-q,--quiet", demo_quiet, "Print nothing but errors and warnings");

  GenerateArgs gen;
  auto* generate_cmd = app.add_subcommand("generate", "Generate the field of a scene and write it (npy, VTK, native)");
  generate_cmd->add_option("scene", gen.scene, "Scene file (JSON)")->required();
  generate_cmd->add_option("-o,--output", gen.out, "Output folder (created if missing)")->required();
  generate_cmd->add_flag("--no-vtk", gen.no_vtk, "Skip the VTK series (.pvd/.vtu)");
  generate_cmd->add_flag("--vtk-pieces", gen.vtk_pieces,
                         "Under mpirun with K > 1 ranks: each rank writes its own piece of every VTK frame "
                         "(field_NNNN.pvtu + field_NNNN_pR.vtu) instead of rank 0 writing field_NNNN.vtu");
  generate_cmd->add_flag("-q,--quiet", gen.quiet, "Print nothing but errors and warnings");

  AnalyzeArgs analyze;
  auto* analyze_cmd = app.add_subcommand(
      "analyze", "Singularities, singularity paths, bifurcations and coherence of a generated field (JSON)");
  analyze_cmd->add_option("input", analyze.input, "Folder written by `tvf generate` (or its field.tvff), or a scene file")
      ->required();
  analyze_cmd->add_option("-o,--output", analyze.out, "Analysis JSON to write")->required();
  analyze_cmd->add_flag("-q,--quiet", analyze.quiet, "Print nothing but errors and warnings");
  analyze_cmd->add_flag("--no-plots", analyze.no_plots,
                        "Skip the pictures (STEM_coherence and STEM_paths, .svg and .png, beside the JSON)");

  std::string validate_path;
  bool validate_domain = false;
  auto* validate_cmd = app.add_subcommand("validate", "Check a scene file (and, with --domain, its mesh)");
  validate_cmd->add_option("scene", validate_path, "Scene file (JSON)")->required();
  validate_cmd->add_flag("--domain", validate_domain,
                         "Also build the domain: loads and checks the mesh, and the scene on it (points far off a "
                         "surface, a sketched streakline that meets itself on it)");

  cli::EditArgs edit;
  auto* edit_cmd = cli::add_edit_command(app, edit);

  cli::ExportArgs export_args;
  auto* export_cmd = cli::add_export_command(app, export_args);

  auto* default_cmd = app.add_subcommand("default-scene", "Print the built-in demo scene (JSON)");
  cli::RenderCommand render(app);
  cli::LcsCommand lcs(app);
  cli::ServeCommand serve(app);
  cli::SynthCommand synth(*app.get_subcommand("render"));

  // Under mpirun every rank parses the same command line and reads the same scene, so an
  // input error is every rank's: rank 0 alone prints it, and every rank exits with its code
  // (mpirun's own exit status is then that code).
  const bool root = distributed_rank() == 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (!root) return e.get_exit_code();
    return app.exit(e);
  }

  // Ctrl-C or SIGTERM during a run removes its staging folders (tvf serve installs its
  // own handlers, which stop the server cleanly instead).
  install_output_cleanup_on_signals();
  try {
    if (*generate_cmd) return run_generate(load_scene(gen.scene), gen, false);
    if (*analyze_cmd) return run_analyze(analyze);
    if (*validate_cmd) return run_validate(validate_path, validate_domain);
    if (*edit_cmd) return cli::run_edit(edit);
    if (*export_cmd) return cli::run_export(export_args);
    if (synth.selected()) return synth.run();
    if (lcs.selected()) return lcs.run();
    if (render.selected()) return render.run();
    if (serve.selected()) return serve.run();
    if (*default_cmd) {
      std::fputs(cli::default_scene_text(), stdout);
      return 0;
    }
    GenerateArgs demo{"", demo_out, false, demo_quiet};
    if (!demo_quiet && root)
      std::printf("tvf: no scene given; generating the built-in demo scene (`tvf default-scene` prints it)\n");
    return run_generate(parse_scene(cli::default_scene_text(), "default scene"), demo, true);
  } catch (const tvf::Error& e) {
    if (root) std::fprintf(stderr, "tvf: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    // Memory runs out on one rank, not on all: each says which it is.
    if (distributed_ranks() > 1)
      std::fprintf(stderr, "tvf: error: out of memory on rank %d of %d\n", distributed_rank(), distributed_ranks());
    else
      std::fprintf(stderr, "tvf: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    if (distributed_ranks() > 1)
      std::fprintf(stderr, "tvf: internal error on rank %d of %d: %s\n", distributed_rank(), distributed_ranks(),
                   e.what());
    else
      std::fprintf(stderr, "tvf: internal error: %s\n", e.what());
    return 2;
  }
}
