#include "support/test_meshes.h"

#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <map>
#include <utility>

namespace tvf::test {

const Mesh& grid_mesh() {
  static const Mesh m = make_grid(GridSpec{17, 13, {-1.0, -0.5}, {2.0, 1.0}});
  return m;
}
const Mesh& icosphere_mesh() {
  static const Mesh m = make_icosphere(3);
  return m;
}
const Mesh& torus_mesh() {
  static const Mesh m = make_torus(24, 12);
  return m;
}
const Mesh& hemisphere_mesh() {
  static const Mesh m = [] {
    const Mesh& s = icosphere_mesh();
    std::vector<int> remap(static_cast<size_t>(s.num_vertices()), -1);
    std::vector<Vec3> pos;
    std::vector<Face> faces;
    for (int f = 0; f < s.num_faces(); ++f) {
      const Face& t = s.face(f);
      bool upper = true;
      for (int v : t) upper = upper && s.position(v).z() > -1e-9;
      if (!upper) continue;
      Face g;
      for (int k = 0; k < 3; ++k) {
        int& r = remap[static_cast<size_t>(t[static_cast<size_t>(k)])];
        if (r < 0) {
          r = static_cast<int>(pos.size());
          pos.push_back(s.position(t[static_cast<size_t>(k)]));
        }
        g[static_cast<size_t>(k)] = r;
      }
      faces.push_back(g);
    }
    return Mesh(std::move(pos), std::move(faces), "hemisphere");
  }();
  return m;
}

const Mesh& slab_mesh() {
  static const Mesh m = [] {
    const int n = 11;
    std::vector<Vec3> x;
    std::vector<Face> faces;
    const auto id = [n](int layer, int i, int j) { return layer * n * n + j * n + i; };
    for (int layer = 0; layer < 2; ++layer)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) x.emplace_back(i / (n - 1.0), j / (n - 1.0), layer == 0 ? kSlabThickness : 0.0);
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        faces.push_back({id(0, i, j), id(0, i + 1, j), id(0, i + 1, j + 1)});
        faces.push_back({id(0, i, j), id(0, i + 1, j + 1), id(0, i, j + 1)});
        faces.push_back({id(1, i, j), id(1, i + 1, j + 1), id(1, i + 1, j)});
        faces.push_back({id(1, i, j), id(1, i, j + 1), id(1, i + 1, j + 1)});
      }
    // The top's rim: its directed edges whose reverse no top face holds.
    std::map<std::pair<int, int>, int> top;
    for (size_t f = 0; f < faces.size(); f += 4)
      for (size_t g = f; g < f + 2; ++g)
        for (size_t k = 0; k < 3; ++k) ++top[{faces[g][k], faces[g][(k + 1) % 3]}];
    const int below = n * n;
    for (const auto& [edge, count] : top) {
      const auto [u, v] = edge;
      if (top.contains({v, u})) continue;
      faces.push_back({v, u, u + below});
      faces.push_back({v, u + below, v + below});
    }
    return Mesh(std::move(x), std::move(faces), "slab");
  }();
  return m;
}

std::vector<NamedMesh> closed_meshes() {
  return {{"icosphere", &icosphere_mesh()}, {"torus", &torus_mesh()}};
}
std::vector<NamedMesh> meshes_with_boundary() {
  return {{"grid", &grid_mesh()}, {"hemisphere", &hemisphere_mesh()}};
}
std::vector<NamedMesh> all_meshes() {
  auto a = closed_meshes();
  auto b = meshes_with_boundary();
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace tvf::test
