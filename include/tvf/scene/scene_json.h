#pragma once
// Reading and writing scenes (DESIGN §10, schema/scene.schema.json, docs/scene_reference.md).
// Every error is a tvf::Error whose message names the file and the JSON path:
//   "scene.json: elements[2].path[1]: t = 7 is outside the time range [0, 1]"
// Unknown keys, wrong types, out-of-range values and non-finite numbers are errors.
#include "tvf/scene/scene.h"

#include <string>

namespace tvf {

// Parses and validates a scene. `label` names the source in messages (usually its path);
// `source_path` (may be empty) is stored in Scene::source_path to resolve mesh paths.
Scene scene_from_json(const nlohmann::json& j, const std::string& label,
                      const std::string& source_path = "");
// Reads a scene file (UTF-8 JSON). Syntax errors name the line and column; every error's
// location() has the file, the JSON path and the line and column of the value.
Scene load_scene(const std::string& path);
// Parses scene text (e.g. the embedded default scene); `label` names it in messages.
Scene parse_scene(const std::string& text, const std::string& label);

// The canonical JSON of a scene: every key written, so that scene_from_json(scene_to_json(s))
// equals s and the output validates against the schema.
nlohmann::json scene_to_json(const Scene& scene);
// Writes the scene (pretty-printed) to a temporary name and renames it when complete.
// A scene that would not load again (it fails validation) is refused with a tvf::Error
// and nothing is written.
void save_scene(const Scene& scene, const std::string& path);
// The text save_scene writes: the canonical JSON of scene_to_json, pretty-printed with the
// keys in the order of DESIGN §10 and short arrays and objects (points, matrices,
// transform keys) kept on one line. Ends with a newline.
std::string scene_to_text(const Scene& scene);
// One key frame as the scene file holds it ({"t", "elements", "streamlines"} or {"t",
// "field"}); `planar`: points written [x, y].
nlohmann::json keyframe_to_json(const Keyframe& keyframe, bool planar);

}  // namespace tvf
