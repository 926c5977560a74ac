#pragma once
// Checks a triangle soup before it becomes a Mesh. Every problem is reported as one
// sentence naming the source and the element ("bunny.obj: face 12 uses vertex 9 twice
// (degenerate face)").
//
// Errors (never repaired): no vertices or no faces; NaN or infinite coordinates; a face
// index out of range; a face repeating a vertex; a face with zero area; an edge shared
// by more than two faces (non-manifold edge); a vertex whose faces form more than one
// fan (non-manifold vertex); neighbouring faces with opposite orientation.
//
// Repairs (done by load_mesh before validation, reported through MeshRepairReport):
// exact duplicate faces (same three vertices in any order) are dropped, and vertices
// referenced by no face are removed (indices compacted), since files exported by
// modelling tools routinely carry both and users expect them to load.
#include "tvf/mesh/mesh.h"

#include <string>
#include <vector>

namespace tvf {

struct MeshRepairReport {
  int duplicate_faces_removed = 0;
  int unreferenced_vertices_removed = 0;
  bool changed() const { return duplicate_faces_removed + unreferenced_vertices_removed > 0; }
};

// The largest coordinate magnitude a mesh (or a grid's box) may have, the scene's own limit
// for numbers: squared distances, areas and the products of the solvers stay finite (1e200
// squared overflows; the tangent frames of such a mesh were NaN). A mesh must also span at
// least kMinRelativeExtent of its largest coordinate, so that its vertices stay distinct
// in double precision.
inline constexpr double kMaxCoordinate = 1e15;
inline constexpr double kMinRelativeExtent = 1e-9;

// Throws tvf::Error on the first problem found. Requires no repairs to be pending
// (unreferenced vertices are an error here).
void validate_triangle_soup(const std::vector<Vec3>& positions, const std::vector<Face>& faces,
                            const std::string& source);

// Drops duplicate faces and unreferenced vertices in place; other problems are left for
// validate_triangle_soup to report.
MeshRepairReport repair_triangle_soup(std::vector<Vec3>& positions, std::vector<Face>& faces);

}  // namespace tvf
