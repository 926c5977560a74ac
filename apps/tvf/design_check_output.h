#pragma once
// `tvf analyze`'s design check (docs/analysis.md, "Design check"): which of the scene's
// designed features the analysis found, and what it found beyond them, written as
// STEM_design.json beside the analysis JSON.
#include "tvf/design/scene.h"
#include "tvf/field/field_io.h"

#include <filesystem>
#include <optional>
#include <string>

namespace tvf::cli {

// The scene that made a generated field: DIR/scene.json for a folder (the scene.json beside
// FILE.tvff for a field file), else the copy stored inside the field file; none when
// neither exists. Throws tvf::Error naming the file when the scene is not valid.
std::optional<Scene> scene_of_field(const std::filesystem::path& input, const FieldFile& file);

// The design-check file written beside `analysis_json`: STEM_design.json.
std::string design_check_path(const std::string& analysis_json);

}  // namespace tvf::cli
