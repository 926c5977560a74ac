#pragma once
// Reading and writing triangle meshes: OBJ, PLY (ASCII and binary) and OFF, chosen by the
// file extension. Reading goes through CGAL's polygon-soup readers, which keep the file's
// vertex order; polygons with more than three corners are triangulated as fans (only
// planar convex polygons are expected). Duplicate faces and unreferenced vertices are
// repaired (mesh_validate.h); everything else that is wrong is an error naming the file.
#include "tvf/mesh/mesh.h"
#include "tvf/mesh/mesh_validate.h"

#include <string>

namespace tvf {

struct LoadedMesh {
  Mesh mesh;
  MeshRepairReport repairs;
};

// Throws tvf::Error naming `path` for a missing or unreadable file, an unknown
// extension, or an invalid mesh.
LoadedMesh load_mesh(const std::string& path);

// Writes OBJ, PLY or OFF by extension (through CGAL's writers). Written to a temporary
// name and renamed when complete.
void save_mesh(const Mesh& mesh, const std::string& path);

}  // namespace tvf
