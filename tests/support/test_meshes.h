#pragma once
// The tests' mesh catalogue (STYLE 11): meshes made once and shared, grouped by kind.
#include "tvf/mesh/mesh.h"

#include <string>
#include <vector>

namespace tvf::test {

struct NamedMesh {
  std::string name;
  const Mesh* mesh;
};

const Mesh& grid_mesh();         // 17 × 13 grid on [-1, 2] × [-0.5, 1]
const Mesh& icosphere_mesh();    // 3 subdivisions, radius 1 (642 vertices)
const Mesh& torus_mesh();        // 24 × 12
const Mesh& hemisphere_mesh();   // upper half of an icosphere: a curved mesh with boundary
// A thin part: the closed slab [0, 1]² × [0, kSlabThickness], 11 × 11 vertices on top and
// on the bottom, their rims joined by a strip (a fiftieth of an edge length high). Not in
// the lists below: its strip's triangles are slivers.
inline constexpr double kSlabThickness = 0.002;
const Mesh& slab_mesh();

std::vector<NamedMesh> closed_meshes();
std::vector<NamedMesh> meshes_with_boundary();
std::vector<NamedMesh> all_meshes();

}  // namespace tvf::test
