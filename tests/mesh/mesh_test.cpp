#include "tvf/mesh/mesh.h"

#include "support/test_meshes.h"
#include "tvf/core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>

namespace tvf {
namespace {

using test::NamedMesh;

TEST(Mesh, HalfedgeNavigationIsConsistent) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    for (int h = 0; h < m.num_halfedges(); ++h) {
      const int f = Mesh::face_of(h);
      EXPECT_EQ(m.tail(h), m.face(f)[static_cast<size_t>(h % 3)]);
      EXPECT_EQ(m.head(h), m.face(f)[static_cast<size_t>((h + 1) % 3)]);
      EXPECT_EQ(Mesh::next(Mesh::next(Mesh::next(h))), h);
      EXPECT_EQ(Mesh::prev(Mesh::next(h)), h);
      EXPECT_EQ(Mesh::face_of(Mesh::next(h)), f);
      EXPECT_EQ(m.head(h), m.tail(Mesh::next(h)));
      const int t = m.twin(h);
      EXPECT_EQ(m.is_boundary_halfedge(h), t < 0);
      if (t < 0) continue;
      EXPECT_NE(t, h);
      EXPECT_NE(Mesh::face_of(t), f);
      EXPECT_EQ(m.twin(t), h);
      EXPECT_EQ(m.tail(t), m.head(h));
      EXPECT_EQ(m.head(t), m.tail(h));
      EXPECT_EQ(m.edge_of(t), m.edge_of(h));
    }
  }
}

TEST(Mesh, EdgesAreTheUndirectedHalfedgePairs) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    std::vector<int> uses(static_cast<size_t>(m.num_edges()), 0);
    for (int h = 0; h < m.num_halfedges(); ++h) {
      const int e = m.edge_of(h);
      ASSERT_GE(e, 0);
      ASSERT_LT(e, m.num_edges());
      ++uses[static_cast<size_t>(e)];
      const auto& ends = m.edge(e);
      EXPECT_EQ(ends[0], std::min(m.tail(h), m.head(h)));
      EXPECT_EQ(ends[1], std::max(m.tail(h), m.head(h)));
    }
    int boundary = 0;
    for (int e = 0; e < m.num_edges(); ++e) {
      EXPECT_TRUE(uses[static_cast<size_t>(e)] == 1 || uses[static_cast<size_t>(e)] == 2);
      boundary += uses[static_cast<size_t>(e)] == 1 ? 1 : 0;
    }
    EXPECT_EQ(boundary, m.num_boundary_edges());
    EXPECT_EQ(2 * m.num_edges(), m.num_halfedges() + m.num_boundary_edges());
  }
}

TEST(Mesh, OutgoingFansAreCounterClockwiseAndCoverEveryHalfedgeOnce) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    std::vector<int> seen(static_cast<size_t>(m.num_halfedges()), 0);
    for (int v = 0; v < m.num_vertices(); ++v) {
      const auto out = m.outgoing(v);
      ASSERT_FALSE(out.empty()) << "vertex " << v;
      // The star's normal (area-weighted) gives "counter-clockwise" its meaning.
      Vec3 n = Vec3::Zero();
      for (int h : out) n += m.face_area(Mesh::face_of(h)) * m.face_normal(Mesh::face_of(h));
      for (size_t k = 0; k < out.size(); ++k) {
        const int h = out[k];
        EXPECT_EQ(m.tail(h), v);
        ++seen[static_cast<size_t>(h)];
        // The next outgoing halfedge is across the edge prev(h) = w→v.
        const int across = m.twin(Mesh::prev(h));
        if (k + 1 < out.size()) {
          EXPECT_EQ(out[k + 1], across) << "vertex " << v;
        } else if (m.is_boundary_vertex(v)) {
          EXPECT_LT(across, 0) << "vertex " << v;
        } else {
          EXPECT_EQ(out[0], across) << "vertex " << v;
        }
        // The sweep from head(h) to the face's third vertex turns counter-clockwise.
        const Vec3 a = m.position(m.head(h)) - m.position(v);
        const Vec3 b = m.position(m.tail(Mesh::prev(h))) - m.position(v);
        EXPECT_GT(a.cross(b).dot(n), 0) << "vertex " << v;
      }
      if (m.is_boundary_vertex(v)) {
        EXPECT_LT(m.twin(out[0]), 0) << "vertex " << v;
      }
    }
    for (int h = 0; h < m.num_halfedges(); ++h) EXPECT_EQ(seen[static_cast<size_t>(h)], 1) << h;
  }
}

TEST(Mesh, BoundaryVertexFlagsMatchBoundaryHalfedges) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    std::vector<char> on_boundary(static_cast<size_t>(m.num_vertices()), 0);
    for (int h = 0; h < m.num_halfedges(); ++h) {
      if (m.twin(h) >= 0) continue;
      on_boundary[static_cast<size_t>(m.tail(h))] = 1;
      on_boundary[static_cast<size_t>(m.head(h))] = 1;
    }
    int count = 0;
    for (int v = 0; v < m.num_vertices(); ++v) {
      EXPECT_EQ(m.is_boundary_vertex(v), on_boundary[static_cast<size_t>(v)] != 0) << v;
      count += on_boundary[static_cast<size_t>(v)];
    }
    // On a manifold every boundary loop has as many vertices as edges.
    EXPECT_EQ(count, m.num_boundary_edges());
    EXPECT_EQ(m.is_closed(), count == 0);
  }
}

TEST(Mesh, EulerCharacteristicOfTheCatalogue) {
  EXPECT_EQ(test::icosphere_mesh().euler_characteristic(), 2);
  EXPECT_EQ(test::torus_mesh().euler_characteristic(), 0);
  EXPECT_EQ(test::grid_mesh().euler_characteristic(), 1);
  EXPECT_EQ(test::hemisphere_mesh().euler_characteristic(), 1);
  for (const NamedMesh& nm : test::closed_meshes()) EXPECT_TRUE(nm.mesh->is_closed()) << nm.name;
  for (const NamedMesh& nm : test::meshes_with_boundary())
    EXPECT_FALSE(nm.mesh->is_closed()) << nm.name;
  const Mesh& s = test::icosphere_mesh();
  EXPECT_EQ(s.num_vertices(), 642);
  EXPECT_EQ(s.num_faces(), 1280);
  EXPECT_EQ(s.num_edges(), 1920);
  EXPECT_EQ(test::torus_mesh().num_vertices(), 24 * 12);
  EXPECT_EQ(test::torus_mesh().num_faces(), 2 * 24 * 12);
}

TEST(Mesh, IcosphereFaceNormalsPointOutward) {
  const Mesh& s = test::icosphere_mesh();
  for (int f = 0; f < s.num_faces(); ++f) {
    const Face& t = s.face(f);
    const Vec3 c = (s.position(t[0]) + s.position(t[1]) + s.position(t[2])) / 3.0;
    const Vec3 n = s.face_normal(f);
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    // Outward and nearly radial on a fine sphere.
    EXPECT_GT(n.dot(c.normalized()), 0.99) << "face " << f;
  }
}

TEST(Mesh, GeometryHelpers) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    for (int f = 0; f < m.num_faces(); ++f) {
      const double sum =
          m.corner_angle(3 * f) + m.corner_angle(3 * f + 1) + m.corner_angle(3 * f + 2);
      EXPECT_NEAR(sum, kPi, 1e-12) << "face " << f;
      EXPECT_GT(m.face_area(f), 0.0);
    }
  }
  const Mesh& g = test::grid_mesh();  // 17 × 13 on [-1, 2] × [-0.5, 1]
  double area = 0;
  for (int f = 0; f < g.num_faces(); ++f) area += g.face_area(f);
  EXPECT_NEAR(area, 3.0 * 1.5, 1e-12);
  EXPECT_EQ(g.bbox_min(), Vec3(-1.0, -0.5, 0.0));
  EXPECT_EQ(g.bbox_max(), Vec3(2.0, 1.0, 0.0));
  EXPECT_DOUBLE_EQ(g.diameter(), std::hypot(3.0, 1.5));
  const Mesh& s = test::icosphere_mesh();
  EXPECT_TRUE((s.bbox_max() - Vec3(1, 1, 1)).cwiseAbs().maxCoeff() < 0.05);
  EXPECT_FALSE(s.is_planar_xy());
  EXPECT_TRUE(g.is_planar_xy());
}

TEST(Mesh, ConstructorValidates) {
  // Two faces using edge 0→1 in the same direction.
  std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  try {
    Mesh(p, {{0, 1, 2}, {0, 1, 3}}, "flipped.obj");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("flipped.obj: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inconsistent orientation"), std::string::npos)
        << e.what();
  }
  const Mesh ok(p, {{0, 1, 2}, {1, 0, 3}}, "ok.obj");
  EXPECT_EQ(ok.num_edges(), 5);
  EXPECT_EQ(ok.num_boundary_edges(), 4);
  EXPECT_EQ(ok.source(), "ok.obj");
}

}  // namespace
}  // namespace tvf
