#include "tvf/mesh/tangent_bundle.h"

#include "support/test_meshes.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace tvf {
namespace {

using test::NamedMesh;

// Angle of z in (−π, π].
double angle_of(cplx z) { return std::arg(z); }
// a − b wrapped to (−π, π].
double angle_diff(double a, double b) { return std::remainder(a - b, 2 * kPi); }

// The rescaling factor of the connection at v: 2π / angle sum at interior vertices whose
// star is not flat, 1 elsewhere (boundary vertices keep their angles).
double scale_at(const TangentBundle& tb, int v) {
  return tb.mesh().is_boundary_vertex(v) ? 1.0 : 2 * kPi / tb.angle_sum(v);
}

Mesh scaled(const Mesh& m, double k) {
  std::vector<Vec3> p = m.positions();
  for (Vec3& x : p) x *= k;
  return Mesh(std::move(p), m.faces(), m.source());
}

// A planar mesh that is not a grid: a 9 × 7 grid with its interior vertices jittered.
Mesh jittered_planar_mesh() {
  const Mesh g = make_grid(GridSpec{9, 7, {-2, -1}, {2, 2}});
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  std::vector<Vec3> p = g.positions();
  for (int v = 0; v < g.num_vertices(); ++v)
    if (!g.is_boundary_vertex(v))
      p[static_cast<size_t>(v)] += Vec3(jitter(rng) * 0.5, jitter(rng) * 0.5, 0);
  return Mesh(std::move(p), g.faces(), "jittered");
}

TEST(TangentBundle, PlanarDomainsAreExactlyFlat) {
  const Mesh jittered = jittered_planar_mesh();
  for (const Mesh* m : {&test::grid_mesh(), &jittered}) {
    SCOPED_TRACE(m->source());
    const TangentBundle tb(*m);
    EXPECT_TRUE(tb.is_flat());
    for (int v = 0; v < m->num_vertices(); ++v) {
      EXPECT_EQ(tb.vertex_normal(v), Vec3(0, 0, 1));
      EXPECT_EQ(tb.vertex_e1(v), Vec3(1, 0, 0));
      EXPECT_EQ(tb.vertex_e2(v), Vec3(0, 1, 0));
    }
    for (int f = 0; f < m->num_faces(); ++f) {
      EXPECT_EQ(tb.face_normal(f), Vec3(0, 0, 1));
      EXPECT_EQ(tb.face_e1(f), Vec3(1, 0, 0));
      EXPECT_EQ(tb.face_e2(f), Vec3(0, 1, 0));
    }
    for (int h = 0; h < m->num_halfedges(); ++h) {
      EXPECT_EQ(tb.transport(h), cplx(1, 0)) << "halfedge " << h;
      EXPECT_EQ(tb.corner_to_face(h), cplx(1, 0)) << "halfedge " << h;
      EXPECT_EQ(tb.face_to_face(h), m->twin(h) < 0 ? cplx(0, 0) : cplx(1, 0)) << "halfedge " << h;
      const Vec3 d = m->position(m->head(h)) - m->position(m->tail(h));
      EXPECT_EQ(tb.halfedge_direction(h), unit_direction(d.x(), d.y()));
    }
  }
}

TEST(TangentBundle, TransportsAreUnitAndTwinsAreConjugate) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const TangentBundle tb(*nm.mesh);
    EXPECT_EQ(tb.is_flat(), nm.name == "grid");
    for (int h = 0; h < nm.mesh->num_halfedges(); ++h) {
      EXPECT_NEAR(std::abs(tb.transport(h)), 1.0, 1e-15);
      EXPECT_NEAR(std::abs(tb.halfedge_direction(h)), 1.0, 1e-15);
      EXPECT_NEAR(std::abs(tb.corner_to_face(h)), 1.0, 1e-15);
      const int t = nm.mesh->twin(h);
      if (t < 0) {
        EXPECT_EQ(tb.face_to_face(h), cplx(0, 0));
        continue;
      }
      EXPECT_NEAR(std::abs(tb.transport(t) - std::conj(tb.transport(h))), 0.0, 1e-12);
      EXPECT_NEAR(std::abs(tb.face_to_face(h)), 1.0, 1e-15);
      EXPECT_NEAR(std::abs(tb.face_to_face(t) - std::conj(tb.face_to_face(h))), 0.0, 1e-12);
    }
  }
}

TEST(TangentBundle, BasesAreOrthonormalTangentAndRightHanded) {
  auto check = [](const Vec3& n, const Vec3& e1, const Vec3& e2) {
    EXPECT_NEAR(n.norm(), 1.0, 1e-14);
    EXPECT_NEAR(e1.norm(), 1.0, 1e-14);
    EXPECT_NEAR(e2.norm(), 1.0, 1e-14);
    EXPECT_NEAR(e1.dot(e2), 0.0, 1e-14);
    EXPECT_NEAR(e1.dot(n), 0.0, 1e-14);
    EXPECT_NEAR(e2.dot(n), 0.0, 1e-14);
    EXPECT_LT((e1.cross(e2) - n).norm(), 1e-14);
  };
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    const TangentBundle tb(m);
    for (int v = 0; v < m.num_vertices(); ++v)
      check(tb.vertex_normal(v), tb.vertex_e1(v), tb.vertex_e2(v));
    for (int f = 0; f < m.num_faces(); ++f) {
      check(tb.face_normal(f), tb.face_e1(f), tb.face_e2(f));
      EXPECT_LT((tb.face_normal(f) - m.face_normal(f)).norm(), 1e-15);
    }
    // Vertex normals point to the side of the faces around them.
    for (int v = 0; v < m.num_vertices(); ++v)
      for (int h : m.outgoing(v))
        EXPECT_GT(tb.vertex_normal(v).dot(m.face_normal(Mesh::face_of(h))), 0.5);
  }
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  for (int k = 0; k < 200; ++k) {
    const Vec3 n = Vec3(g(rng), g(rng), g(rng)).normalized();
    Vec3 e1, e2;
    tangent_basis(n, e1, e2);
    check(n, e1, e2);
  }
  Vec3 e1, e2;
  tangent_basis(Vec3(0, 0, 1), e1, e2);
  EXPECT_EQ(e1, Vec3(1, 0, 0));
  EXPECT_EQ(e2, Vec3(0, 1, 0));
  tangent_basis(Vec3(1, 0, 0), e1, e2);  // x is the normal: the basis starts from y
  EXPECT_EQ(e1, Vec3(0, 1, 0));
  EXPECT_EQ(e2, Vec3(0, 0, 1));
}

TEST(TangentBundle, WorldConversionsRoundTrip) {
  const Mesh& m = test::torus_mesh();
  const TangentBundle tb(m);
  const cplx z(0.3, -1.7);
  for (int v = 0; v < m.num_vertices(); ++v) {
    EXPECT_NEAR(std::abs(tb.world_to_vertex(v, tb.vertex_to_world(v, z)) - z), 0.0, 1e-14);
    EXPECT_NEAR(std::abs(tb.world_to_vertex(v, tb.vertex_normal(v))), 0.0, 1e-14);
  }
  for (int f = 0; f < m.num_faces(); ++f) {
    EXPECT_NEAR(std::abs(tb.world_to_face(f, tb.face_to_world(f, z)) - z), 0.0, 1e-14);
    EXPECT_NEAR(std::abs(tb.world_to_face(f, tb.face_normal(f))), 0.0, 1e-14);
  }
}

TEST(TangentBundle, DirectionsSweepTheRescaledCornerAngles) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    const TangentBundle tb(m);
    for (int v = 0; v < m.num_vertices(); ++v) {
      const auto out = m.outgoing(v);
      const double s = scale_at(tb, v);
      double sum = 0;
      for (size_t k = 0; k < out.size(); ++k) {
        sum += m.corner_angle(out[k]);
        if (k + 1 == out.size() && m.is_boundary_vertex(v)) break;
        const int h = out[k], g = out[(k + 1) % out.size()];
        const double turn = angle_of(tb.halfedge_direction(g) / tb.halfedge_direction(h));
        EXPECT_NEAR(angle_diff(turn, s * m.corner_angle(h)), 0.0, 1e-12) << "vertex " << v;
      }
      EXPECT_NEAR(tb.angle_sum(v), sum, 1e-12);
      // The first direction is the first edge projected onto the tangent plane.
      const Vec3 e = m.position(m.head(out[0])) - m.position(v);
      const cplx projected = tb.world_to_vertex(v, e);
      EXPECT_NEAR(angle_diff(angle_of(tb.halfedge_direction(out[0])), angle_of(projected)), 0.0,
                  1e-12);
    }
  }
}

TEST(TangentBundle, GaussBonnetForAngleDefects) {
  for (const NamedMesh& nm : test::all_meshes()) {
    const TangentBundle tb(*nm.mesh);
    double total = 0;
    for (int v = 0; v < nm.mesh->num_vertices(); ++v) total += tb.angle_defect(v);
    EXPECT_NEAR(total, 2 * kPi * nm.mesh->euler_characteristic(), 1e-9) << nm.name;
  }
}

TEST(TangentBundle, FaceToFaceHolonomyAroundAVertexIsItsAngleDefect) {
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    const TangentBundle tb(m);
    int interior = 0;
    for (int v = 0; v < m.num_vertices(); ++v) {
      if (m.is_boundary_vertex(v)) continue;
      ++interior;
      // Counter-clockwise from face_of(h) to face_of(twin(prev(h))), across prev(h).
      cplx holonomy(1, 0);
      for (int h : m.outgoing(v)) holonomy *= tb.face_to_face(Mesh::prev(h));
      EXPECT_NEAR(std::abs(holonomy - std::polar(1.0, tb.angle_defect(v))), 0.0, 1e-10)
          << "vertex " << v << ", defect " << tb.angle_defect(v);
    }
    EXPECT_GT(interior, 0);
  }
}

TEST(TangentBundle, FaceHolonomyOfTheVertexConnection) {
  // Around face ijk, r_ki·r_jk·r_ij rotates by Σ over its corners of (s_v − 1)·α_v:
  // the defect of each vertex, handed to its faces in proportion to their angles. Summed
  // over a closed mesh that is 2πχ (discrete Gauss–Bonnet for the connection).
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    const TangentBundle tb(m);
    double total = 0, interior_defects = 0;
    for (int f = 0; f < m.num_faces(); ++f) {
      cplx loop(1, 0);
      double expected = 0;
      for (int c = 0; c < 3; ++c) {
        const int h = 3 * f + c;
        loop = tb.transport(h) * loop;
        expected += (scale_at(tb, m.tail(h)) - 1.0) * m.corner_angle(h);
      }
      EXPECT_NEAR(angle_diff(angle_of(loop), expected), 0.0, 1e-10) << "face " << f;
      total += angle_of(loop);
    }
    for (int v = 0; v < m.num_vertices(); ++v)
      if (!m.is_boundary_vertex(v)) interior_defects += tb.angle_defect(v);
    EXPECT_NEAR(total, interior_defects, 1e-9);
    if (m.is_closed()) {
      EXPECT_NEAR(total, 2 * kPi * m.euler_characteristic(), 1e-9);
    }
  }
}

TEST(TangentBundle, CornerToFaceAgreesWithTransportUpToTheRescaling) {
  // Carrying a vector from T_i to T_j (transport) and then into face f (corner_to_face at
  // j) differs from carrying it into f directly at i only by the halves of the angle
  // rescaling at i and j that the bisector rule assigns to edge ij:
  //   c2f(next(h)) · r_ij = c2f(h) · exp(−i·((1 − s_i)·α_i + (1 − s_j)·α_j) / 2).
  // Where no rescaling happens (planar or developable) the two ways agree.
  for (const NamedMesh& nm : test::all_meshes()) {
    SCOPED_TRACE(nm.name);
    const Mesh& m = *nm.mesh;
    const TangentBundle tb(m);
    for (int h = 0; h < m.num_halfedges(); ++h) {
      const int n = Mesh::next(h);
      const double beta = 0.5 * ((1 - scale_at(tb, m.tail(h))) * m.corner_angle(h) +
                                 (1 - scale_at(tb, m.tail(n))) * m.corner_angle(n));
      const cplx lhs = tb.corner_to_face(n) * tb.transport(h);
      const cplx rhs = tb.corner_to_face(h) * std::polar(1.0, -beta);
      EXPECT_NEAR(std::abs(lhs - rhs), 0.0, 1e-12) << "halfedge " << h;
      if (tb.is_flat()) {
        EXPECT_EQ(lhs, tb.corner_to_face(h));
      }
    }
  }
}

TEST(TangentBundle, UnchangedByUniformScaling) {
  for (const NamedMesh& nm : test::all_meshes()) {
    const TangentBundle tb(*nm.mesh);
    for (double k : {1000.0, 1e-3}) {
      SCOPED_TRACE(::testing::Message() << nm.name << " × " << k);
      const Mesh sm = scaled(*nm.mesh, k);
      const TangentBundle ts(sm);
      EXPECT_EQ(ts.is_flat(), tb.is_flat());
      for (int h = 0; h < sm.num_halfedges(); ++h) {
        EXPECT_NEAR(std::abs(ts.transport(h) - tb.transport(h)), 0.0, 1e-12);
        EXPECT_NEAR(std::abs(ts.halfedge_direction(h) - tb.halfedge_direction(h)), 0.0, 1e-12);
        EXPECT_NEAR(std::abs(ts.corner_to_face(h) - tb.corner_to_face(h)), 0.0, 1e-12);
        EXPECT_NEAR(std::abs(ts.face_to_face(h) - tb.face_to_face(h)), 0.0, 1e-12);
        if (tb.is_flat()) {
          EXPECT_EQ(ts.transport(h), cplx(1, 0));
        }
      }
      for (int v = 0; v < sm.num_vertices(); ++v) {
        EXPECT_LT((ts.vertex_e1(v) - tb.vertex_e1(v)).norm(), 1e-12);
        EXPECT_LT((ts.vertex_normal(v) - tb.vertex_normal(v)).norm(), 1e-12);
        EXPECT_NEAR(ts.angle_sum(v), tb.angle_sum(v), 1e-12);
      }
      for (int f = 0; f < sm.num_faces(); ++f)
        EXPECT_LT((ts.face_e1(f) - tb.face_e1(f)).norm(), 1e-12);
    }
  }
}

}  // namespace
}  // namespace tvf
