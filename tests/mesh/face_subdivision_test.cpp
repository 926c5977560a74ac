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

TEST(FaceSubdivision, RejectsAnOutOfRangeCount) {
  const Mesh grid = make_grid(GridSpec{3, 3, {0, 0}, {1, 1}});
  EXPECT_NE(test::error_of([&] { subdivide_faces(grid, 0); }).find("face subdivision 0"), std::string::npos);
  EXPECT_NE(test::error_of([&] { subdivide_faces(grid, 65); }).find("[1, 64]"), std::string::npos);
}

}  // namespace
}  // namespace tvf
