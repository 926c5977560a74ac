#include "design_check_output.h"

#include "tvf/core/error.h"
#include "tvf/design/scene_json.h"

namespace fs = std::filesystem;

namespace tvf::cli {

std::optional<Scene> scene_of_field(const fs::path& input, const FieldFile& file) {
  std::error_code ec;
  const fs::path folder = fs::is_directory(input, ec) ? input : input.parent_path();
  const fs::path beside = folder / "scene.json";
  if (fs::exists(beside, ec)) return load_scene(beside.string());
  if (file.scene.is_null()) return std::nullopt;
  const std::string label = input.string() + " (its scene)";
  Scene scene = scene_from_json(file.scene, label, beside.string());
  // The copy inside the file was written with the field: one that does not describe this
  // field (a spliced or corrupt file) is refused rather than checked against the wrong design.
  const TimeSampling& t = file.field.time();
  if (scene.time.t0 != t.t0 || scene.time.t1 != t.t1 || scene.time.frames != t.frames)
    throw Error(fmt::format("{}: time: the scene's {} frames over [{}, {}] do not match the field's {} frames over "
                            "[{}, {}] (the file is corrupt)",
                            label, scene.time.frames, scene.time.t0, scene.time.t1, t.frames, t.t0, t.t1));
  if (const auto& g = scene.domain.grid) {
    if (!file.mesh.is_planar_xy() ||
        static_cast<long long>(g->nx) * g->ny != static_cast<long long>(file.mesh.num_vertices()))
      throw Error(fmt::format("{}: domain.grid: a grid of {} × {} vertices does not match the field's mesh of {} "
                              "vertices (the file is corrupt)",
                              label, g->nx, g->ny, file.mesh.num_vertices()));
  } else if ((scene.domain.sphere || scene.domain.torus) && file.mesh.is_planar_xy()) {
    throw Error(fmt::format("{}: domain: the scene's surface does not match the field's planar mesh (the file is "
                            "corrupt)",
                            label));
  }
  return scene;
}

std::string design_check_path(const std::string& analysis_json) {
  const fs::path out(analysis_json);
  return ((out.parent_path() / out.stem()).string() + "_design.json");
}

}  // namespace tvf::cli
