#include "edit_command.h"

#include "progress.h"

#include "tvf/api/design.h"
#include "tvf/core/error.h"
#include "tvf/scene/scene_json.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>

namespace tvf::cli {

CLI::App* add_edit_command(CLI::App& app, EditArgs& args) {
  auto* cmd = app.add_subcommand(
      "edit", "Append a topological edit to a scene's edits (checked on the generated field first), or undo the last");
  cmd->add_option("scene", args.scene, "Scene file (JSON), rewritten in place")->required();
  auto* cancel = cmd->add_option("--cancel", args.cancel,
                                 "FRAME X1 Y1 X2 Y2: cancel the pair of singularities nearest to the two positions "
                                 "at FRAME (X Y Z on surfaces)")
                     ->expected(5, 7);
  auto* remove = cmd->add_option("--remove-bifurcation", args.remove_bifurcation,
                                 "T X Y: remove the bifurcation nearest to (X, Y) at time T (T X Y Z on surfaces)")
                     ->expected(3, 4);
  auto* move = cmd->add_option("--move-bifurcation", args.move_bifurcation,
                               "T X Y T2 X2 Y2: move the bifurcation nearest to (X, Y) at T to (X2, Y2) at T2 "
                               "(T X Y Z T2 X2 Y2 Z2 on surfaces)")
                   ->expected(6, 8);
  auto* smooth = cmd->add_option("--smooth", args.smooth, "S: smooth the whole field in space and time, S in (0, 1]");
  auto* undo = cmd->add_flag("--undo", args.undo, "Drop the last edit");
  cmd->add_option("--window", args.window,
                  "Half-width of the time window re-solved around the edit, as a fraction of the time range "
                  "(default 0.1)");
  cmd->add_flag("-q,--quiet", args.quiet, "Print nothing but errors and warnings");
  cancel->excludes(remove, move, smooth, undo);
  remove->excludes(move, smooth, undo);
  move->excludes(smooth, undo);
  smooth->excludes(undo);
  return cmd;
}

namespace {

nlohmann::json position_json(const std::vector<double>& v, size_t at, size_t n) {
  nlohmann::json p = nlohmann::json::array();
  for (size_t i = 0; i < n; ++i) p.push_back(v[at + i]);
  return p;
}

// The edit the arguments ask for, as a scene entry (validated with the scene).
nlohmann::json requested_edit(const EditArgs& args, const Scene& scene) {
  const bool planar = scene.domain.is_planar();
  const size_t n = planar ? 2 : 3;
  const std::string form = planar ? "X Y" : "X Y Z";
  nlohmann::json e;
  auto window = [&] {
    if (!std::isnan(args.window)) e["window"] = args.window;
  };
  if (!args.cancel.empty()) {
    if (args.cancel.size() != 1 + 2 * n)
      throw Error(fmt::format("{0}: --cancel needs FRAME {1} {1} ({2} numbers) on this {3} domain, got {4}",
                              args.scene, form, 1 + 2 * n, planar ? "planar" : "surface", args.cancel.size()));
    const double frame = args.cancel[0];
    if (frame != std::floor(frame) || frame < 0 || frame >= scene.time.frames)
      throw Error(fmt::format("{}: --cancel: FRAME must be an integer in [0, {}], got {}", args.scene,
                              scene.time.frames - 1, frame));
    e = {{"op", "cancel"},
         {"frame", static_cast<int>(frame)},
         {"pair", nlohmann::json::array({position_json(args.cancel, 1, n), position_json(args.cancel, 1 + n, n)})}};
    window();
  } else if (!args.remove_bifurcation.empty()) {
    if (args.remove_bifurcation.size() != 1 + n)
      throw Error(fmt::format("{}: --remove-bifurcation needs T {} ({} numbers) on this domain", args.scene, form,
                              1 + n));
    nlohmann::json at = position_json(args.remove_bifurcation, 1, n);
    at.push_back(args.remove_bifurcation[0]);
    e = {{"op", "remove_bifurcation"}, {"at", at}};
    window();
  } else if (!args.move_bifurcation.empty()) {
    if (args.move_bifurcation.size() != 2 * (1 + n))
      throw Error(fmt::format("{}: --move-bifurcation needs T {} T2 {} ({} numbers) on this {} domain, got {}",
                              args.scene, form, form, 2 * (1 + n), planar ? "planar" : "surface",
                              args.move_bifurcation.size()));
    nlohmann::json at = position_json(args.move_bifurcation, 1, n),
                   to = position_json(args.move_bifurcation, 2 + n, n);
    at.push_back(args.move_bifurcation[0]);
    to.push_back(args.move_bifurcation[1 + n]);
    e = {{"op", "move_bifurcation"}, {"at", at}, {"to", to}};
    window();
  } else {
    e = {{"op", "smooth"}, {"strength", args.smooth}};
  }
  return e;
}

}  // namespace

int run_edit(const EditArgs& args) {
  const bool given = !args.cancel.empty() || !args.remove_bifurcation.empty() || !args.move_bifurcation.empty() ||
                     !std::isnan(args.smooth) || args.undo;
  if (!given)
    throw Error(fmt::format("{}: say which edit: --cancel, --remove-bifurcation, --move-bifurcation, --smooth or --undo",
                            args.scene));
  // --window belongs to the edits that re-solve a time window; it is never dropped or
  // replaced silently.
  if (!std::isnan(args.window)) {
    if (!std::isnan(args.smooth) || args.undo)
      throw Error(fmt::format("{}: --window applies to --cancel, --remove-bifurcation and --move-bifurcation; {} "
                              "has no time window",
                              args.scene, args.undo ? "--undo" : "--smooth (which smooths every frame)"));
    if (!(args.window >= 0 && args.window <= 1))
      throw Error(fmt::format("{}: --window {}: must be in [0, 1] (a fraction of the time range)", args.scene,
                              args.window));
  }
  Scene scene = load_scene(args.scene);
  if (args.undo) {
    if (scene.edits.empty()) throw Error(fmt::format("{}: the scene has no edits to undo", args.scene));
    const nlohmann::json dropped = edit_to_json(scene.edits.back(), scene.domain.is_planar());
    scene.edits.pop_back();
    save_scene(scene, args.scene);
    if (!args.quiet)
      std::printf("%s: dropped the last edit (%s); %zu edits left\n", args.scene.c_str(), dropped.dump().c_str(),
                  scene.edits.size());
    return 0;
  }
  // Through the library's facade (api/design.h), as the server and Python edit: the new
  // entry is validated with the scene (JSON paths name it), then checked on the field the
  // scene makes now; a refused edit changes nothing.
  const bool show = !args.quiet && progress_wanted();
  Progress progress("tvf edit", show);
  Design design(std::move(scene));
  GenerateOptions options;
  options.progress = [&](int done, int total) { progress.update(done, total); };
  options.stage = [&](const std::string& what) { progress.note(what); };
  progress.note("generating, then applying the edit");
  const EditReport report = design.edit(requested_edit(args, design.scene()), options);
  progress.note("writing " + args.scene);
  design.save(args.scene);
  progress.finish();
  if (!args.quiet)
    std::printf("%s: %s; appended as edits[%zu]\n", args.scene.c_str(), report.summary.c_str(),
                design.scene().edits.size() - 1);
  return 0;
}

}  // namespace tvf::cli
