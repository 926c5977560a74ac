#pragma once
// The native field file (`field.tvff`): reloads exactly what `tvf generate` produced —
// mesh, time sampling, field (double precision) and the scene that made it.
// Layout (little-endian): 8-byte magic "TVFFIELD", uint32 format version (1), uint64
// header length, a UTF-8 JSON header {"vertices", "faces", "frames", "t0", "t1",
// "scene"}, then positions (|V|×3 float64), faces (|F|×3 int32), field values
// (N×|V|×2 float64, frame-major, re/im in each vertex's tangent basis). The tangent bases
// are a deterministic function of the mesh (tangent_bundle.h), so they are not stored.
#include "tvf/field/field.h"
#include "tvf/mesh/mesh.h"

#include <nlohmann/json.hpp>

#include <string>

namespace tvf {

struct FieldFile {
  Mesh mesh;
  Field field;
  nlohmann::json scene;  // the scene JSON as written (scene_to_json), or null
};

void save_field_file(const std::string& path, const Mesh& mesh, const Field& field,
                     const nlohmann::json& scene);
// Throws tvf::Error naming `path` for a missing, truncated or foreign file.
FieldFile load_field_file(const std::string& path);

}  // namespace tvf
