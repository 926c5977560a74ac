#include "design_check_output.h"

#include "tvf/design/scene_json.h"

namespace fs = std::filesystem;

namespace tvf::cli {

std::optional<Scene> scene_of_field(const fs::path& input, const FieldFile& file) {
  std::error_code ec;
  const fs::path folder = fs::is_directory(input, ec) ? input : input.parent_path();
  const fs::path beside = folder / "scene.json";
  if (fs::exists(beside, ec)) return load_scene(beside.string());
  if (!file.scene.is_null()) return scene_from_json(file.scene, input.string() + " (its scene)", beside.string());
  return std::nullopt;
}

std::string design_check_path(const std::string& analysis_json) {
  const fs::path out(analysis_json);
  return ((out.parent_path() / out.stem()).string() + "_design.json");
}

}  // namespace tvf::cli
