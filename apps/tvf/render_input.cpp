#include "render_input.h"

#include "tvf/api/design.h"
#include "tvf/core/error.h"

#include <fmt/format.h>

namespace tvf::cli {

// Reads a field (folder or .tvff) or generates one from a scene, through the library's
// facade (api/design.h: the same messages for a missing input as every command); planar
// domains only unless `surfaces` (texture animation draws both).
RenderInput load_render_input(const std::string& input_name, Progress& progress, const char* kind, bool surfaces) {
  const std::string surface_note = fmt::format(
      "the domain is a surface: `tvf render {}` draws planar domains only (`tvf render texture` draws surfaces)", kind);
  progress.note("reading the input");
  Design design = Design::open(input_name);
  std::vector<std::string> warnings;
  if (!design.has_field()) {
    // A scene file: refused before generating when the domain is a surface.
    progress.note("building the domain");
    if (!design.space().planar() && !surfaces) throw Error(fmt::format("{}: {}", input_name, surface_note));
    GenerateOptions gen;
    gen.progress = [&](int done, int total) { progress.update(done, total); };
    gen.stage = [&](const std::string& what) { progress.note(what); };
    design.generate(gen);
    warnings = design.report().warnings;
  }
  RenderInput in(design.field_space(), design.field_ptr(), std::move(warnings));
  if (design.has_scene()) in.scene = design.scene();
  if (!in.mesh.is_planar_xy() && !surfaces) throw Error(fmt::format("{}: {}", input_name, surface_note));
  return in;
}

}  // namespace tvf::cli
