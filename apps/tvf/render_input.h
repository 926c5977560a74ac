#pragma once
// The field a `tvf render` kind (and ftle, streaklines, timelines, synth) draws: read from
// a folder or .tvff written by `tvf generate`, or generated from a scene file (with
// progress on a terminal), through tvf::Design.
#include "progress.h"

#include "tvf/field/field.h"
#include "tvf/mesh/mesh.h"
#include "tvf/scene/design_space.h"

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tvf::cli {

struct RenderInput {
  RenderInput(std::shared_ptr<const DesignSpace> s, std::shared_ptr<const Field> f, std::vector<std::string> w)
      : space(std::move(s)), field_data(std::move(f)), mesh(space->mesh()), field(*field_data),
        warnings(std::move(w)) {}
  std::shared_ptr<const DesignSpace> space;  // the domain: mesh and tangent bundle
  std::shared_ptr<const Field> field_data;
  const Mesh& mesh;    // space->mesh()
  const Field& field;  // *field_data
  std::vector<std::string> warnings;  // the generation's, printed after the render
  std::optional<Scene> scene;         // the input's scene, when it has one
};

// Throws tvf::Error naming the input. Planar domains only unless `surfaces`; `kind`
// names the render command in that error.
RenderInput load_render_input(const std::string& input_name, Progress& progress, const char* kind, bool surfaces);

}  // namespace tvf::cli
