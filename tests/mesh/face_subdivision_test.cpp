// Face subdivision: the vertex count of its formula, the same surface (Euler
// characteristic, area, original vertices kept), every new vertex where its barycentric
// coordinates say, edges 1/n as long.
#include "tvf/mesh/face_subdivision.h"

#include "support/test_paths.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

namespace tvf {
namespace {

double area(const Mesh& mesh) {
  double a = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& c = mesh.face(f);
    a += 0.5 * (mesh.position(c[1]) - mesh.position(c[0])).cross(mesh.position(c[2]) - mesh.position(c[0])).norm();
  }
  return a;
}

TEST(FaceSubdivision, KeepsTheSurfaceAndPlacesEveryVertex) {
  const Mesh sphere = make_icosphere(2);
  const Mesh grid = make_grid(GridSpec{4, 3, {-1, -1}, {2, 1}});  // with boundary
  for (const Mesh* mesh : {&sphere, &grid})
    for (int n : {1, 2, 3, 5}) {
      const FaceSubdivision s = subdivide_faces(*mesh, n);
      EXPECT_EQ(s.n, n);
      ASSERT_EQ(s.mesh.num_vertices(), subdivision_vertex_count(*mesh, n));
      EXPECT_EQ(s.mesh.num_faces(), mesh->num_faces() * n * n);
      EXPECT_EQ(s.mesh.euler_characteristic(), mesh->euler_characteristic());
      EXPECT_NEAR(area(s.mesh), area(*mesh), 1e-9 * area(*mesh));
      for (int v = 0; v < mesh->num_vertices(); ++v) EXPECT_EQ(s.mesh.position(v), mesh->position(v));
      for (int v = 0; v < s.mesh.num_vertices(); ++v) {
        const Face& c = mesh->face(s.face[static_cast<size_t>(v)]);
        const Vec3& b = s.bary[static_cast<size_t>(v)];
        EXPECT_NEAR(b.sum(), 1.0, 1e-12);
        const Vec3 p = b[0] * mesh->position(c[0]) + b[1] * mesh->position(c[1]) + b[2] * mesh->position(c[2]);
        EXPECT_LT((p - s.mesh.position(v)).norm(), 1e-12) << v;
      }
      // Every small edge is parallel to a side of its face and 1/n as long (the mix of
      // sides differs a little, so the mean is near, not equal).
      EXPECT_NEAR(s.mesh.mean_edge_length(), mesh->mean_edge_length() / n, 0.1 * mesh->mean_edge_length() / n);
    }
}

// The lattice of every face: point (i, j) is the vertex at barycentric (n − i − j, i, j)/n
// of that face, shared with the neighbouring face along an edge, and the corners are the
// face's own vertices.
TEST(FaceSubdivision, EachFacesLatticeNamesTheVertexAtItsPoint) {
  const Mesh sphere = make_icosphere(1);
  for (int n : {1, 2, 4}) {
    const FaceSubdivision s = subdivide_faces(sphere, n);
    ASSERT_EQ(s.grid.size(), static_cast<size_t>(sphere.num_faces() * (n + 1) * (n + 2) / 2));
    for (int f = 0; f < sphere.num_faces(); ++f) {
      const Face& c = sphere.face(f);
      EXPECT_EQ(s.vertex(f, 0, 0), c[0]);
      EXPECT_EQ(s.vertex(f, n, 0), c[1]);
      EXPECT_EQ(s.vertex(f, 0, n), c[2]);
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i + j <= n; ++i) {
          const Vec3 p = (static_cast<double>(n - i - j) * sphere.position(c[0]) + static_cast<double>(i) * sphere.position(c[1]) +
                          static_cast<double>(j) * sphere.position(c[2])) / n;
          EXPECT_LT((s.mesh.position(s.vertex(f, i, j)) - p).norm(), 1e-12) << f << " " << i << " " << j;
        }
    }
  }
}

TEST(FaceSubdivision, RejectsAnOutOfRangeCount) {
  const Mesh grid = make_grid(GridSpec{3, 3, {0, 0}, {1, 1}});
  EXPECT_NE(test::error_of([&] { subdivide_faces(grid, 0); }).find("face subdivision 0"), std::string::npos);
  EXPECT_NE(test::error_of([&] { subdivide_faces(grid, 65); }).find("[1, 64]"), std::string::npos);
}

}  // namespace
}  // namespace tvf
