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

std::vector<NamedMesh> closed_meshes();
std::vector<NamedMesh> meshes_with_boundary();
std::vector<NamedMesh> all_meshes();

}  // namespace tvf::test
