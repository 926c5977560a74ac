#include "render_input.h"

#include "tvf/core/error.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"

#include <fmt/format.h>

#include <filesystem>

namespace fs = std::filesystem;

namespace tvf::cli {

// Reads a field (folder or .tvff) or generates one from a scene; planar domains only
// unless `surfaces` (texture animation draws both).
RenderInput load_render_input(const std::string& input_name, Progress& progress, const char* kind, bool surfaces) {
  const fs::path input(input_name);
  std::error_code ec;
  if (!fs::exists(input, ec))
    throw Error(fmt::format("{}: no such file or folder (give a folder written by `tvf generate`, "
                            "its field.tvff, or a scene file)", input_name));
  const std::string surface_note = fmt::format(
      "the domain is a surface: `tvf render {}` draws planar domains only (`tvf render texture` draws surfaces)", kind);
  RenderInput in;
  if (fs::is_directory(input, ec) || input.extension() == ".tvff") {
    const fs::path file = fs::is_directory(input, ec) ? input / "field.tvff" : input;
    if (!fs::exists(file, ec))
      throw Error(fmt::format("{}: no field.tvff in this folder (write one with `tvf generate SCENE -o {}`)",
                              input_name, input_name));
    progress.note("reading the field");
    FieldFile ff = load_field_file(file.string());
    in.mesh = std::move(ff.mesh);
    in.field = std::move(ff.field);
  } else {
    const Scene scene = load_scene(input_name);
    progress.note("building the domain");
    const auto space = make_design_space(scene);
    if (!space->planar() && !surfaces) throw Error(fmt::format("{}: {}", input_name, surface_note));
    GenerateOptions gen;
    gen.progress = [&](int done, int total) { progress.update(done, total); };
    GenerateReport report;
    in.field = generate(*space, scene, gen, &report);
    in.warnings = report.warnings;
    in.mesh = space->mesh();
  }
  if (!in.mesh.is_planar_xy() && !surfaces) throw Error(fmt::format("{}: {}", input_name, surface_note));
  return in;
}

}  // namespace tvf::cli
