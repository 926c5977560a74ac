#pragma once
// The field a `tvf render` kind draws: read from a folder or .tvff written by
// `tvf generate`, or generated from a scene file (with progress on a terminal).
#include "progress.h"

#include "tvf/field/field.h"
#include "tvf/mesh/mesh.h"

#include <string>
#include <vector>

namespace tvf::cli {

struct RenderInput {
  Mesh mesh;
  Field field;
  std::vector<std::string> warnings;  // the generation's, printed after the render
};

// Throws tvf::Error naming the input. Planar domains only unless `surfaces`; `kind`
// names the render command in that error.
RenderInput load_render_input(const std::string& input_name, Progress& progress, const char* kind, bool surfaces);

}  // namespace tvf::cli
