#include "tvf/mesh/intrinsic_triangulation.h"

#include "support/test_meshes.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

namespace tvf {
namespace {

// A sheared grid of nx × ny vertices (x + shear·y, y·aspect) whose quads are split along
// the long diagonal: far from Delaunay (opposite angles of the long diagonals near π).
// Rotated by `rotation` (identity: the z = 0 plane, a flat bundle).
Mesh sheared_grid(int nx, int ny, double shear, double aspect, const Eigen::Matrix3d& rotation) {
  std::vector<Vec3> p;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) p.push_back(rotation * Vec3(i + shear * j, aspect * j, 0.0));
  std::vector<Face> f;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      f.push_back({a, b, d});  // the long diagonal a–d (shear > 0)
      f.push_back({a, d, c});
    }
  return Mesh(std::move(p), std::move(f), "sheared grid");
}

Eigen::Matrix3d tilt() { return Eigen::AngleAxisd(0.7, Vec3(1, 2, 0.5).normalized()).toRotationMatrix(); }

TEST(IntrinsicTriangulation, DelaunayMeshesAreKeptAsTheyAre) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const IntrinsicTriangulation idt(bundle);
    EXPECT_TRUE(idt.is_input()) << name << ": " << idt.flips() << " flips, δ = " << idt.mollification();
    for (int h = 0; h < idt.num_halfedges(); ++h) {
      ASSERT_EQ(idt.input_halfedge(h), h) << name;
      ASSERT_EQ(idt.transport(h), bundle.transport(h)) << name;
      ASSERT_EQ(idt.direction(h), bundle.halfedge_direction(h)) << name;
    }
  }
}

TEST(IntrinsicTriangulation, FlipsANonDelaunayPlaneToNonNegativeWeightsWithTransportsExactlyOne) {
  const Mesh mesh = sheared_grid(9, 7, 0.8, 0.3, Eigen::Matrix3d::Identity());
  const TangentBundle bundle(mesh);
  const IntrinsicTriangulation idt(bundle);
  EXPECT_LT(idt.min_input_weight(), -1.0);
  EXPECT_GT(idt.flips(), 20);
  EXPECT_EQ(idt.mollification(), 0.0);
  for (int h = 0; h < idt.num_halfedges(); ++h) {
    if (idt.twin(h) >= 0) {
      EXPECT_GE(0.5 * (idt.cot_opposite(h) + idt.cot_opposite(idt.twin(h))), -1e-10);
    }
    EXPECT_EQ(idt.transport(h), cplx(1, 0));
    // In the plane an intrinsic edge is the segment between its ends.
    EXPECT_NEAR(idt.length(h), (mesh.position(idt.head(h)) - mesh.position(idt.tail(h))).norm(), 1e-12);
  }
}

// In any plane, Delaunay or not: a constant world vector is parallel (every intrinsic
// edge's transport carries it to itself), and the intrinsic cotan weights have linear
// precision (Σ_j w_ij (x_j − x_i) = 0 at interior vertices). The tilted plane takes
// TangentBundle's general path (angles), so the flipped edges' transports are tested.
TEST(IntrinsicTriangulation, TiltedPlaneKeepsParallelVectorsAndLinearPrecision) {
  const Mesh mesh = sheared_grid(9, 7, 0.8, 0.3, tilt());
  const TangentBundle bundle(mesh);
  ASSERT_FALSE(bundle.is_flat());
  const IntrinsicTriangulation idt(bundle);
  ASSERT_GT(idt.flips(), 20);
  const Vec3 w = tilt() * Vec3(0.6, -0.8, 0);
  int flipped = 0;
  for (int h = 0; h < idt.num_halfedges(); ++h) {
    const int i = idt.tail(h), j = idt.head(h);
    const cplx zi = bundle.world_to_vertex(i, w), zj = bundle.world_to_vertex(j, w);
    EXPECT_LT(std::abs(idt.transport(h) * zi - zj), 1e-12) << h;
    // The direction of an edge at its tail is the segment's direction there.
    const cplx seg = normalized(bundle.world_to_vertex(i, mesh.position(j) - mesh.position(i)));
    EXPECT_LT(std::abs(idt.direction(h) - seg), 1e-12) << h;
    if (idt.input_halfedge(h) < 0) ++flipped;
  }
  EXPECT_GT(flipped, 0);
  std::vector<Vec3> sum(static_cast<size_t>(mesh.num_vertices()), Vec3::Zero());
  for (int h = 0; h < idt.num_halfedges(); ++h) {
    const int i = idt.tail(h), j = idt.head(h);
    // Each interior edge is seen from both halfedges; a boundary edge once (added both ways).
    sum[static_cast<size_t>(i)] += idt.edge_weight(h) * (mesh.position(j) - mesh.position(i));
    if (idt.twin(h) < 0) sum[static_cast<size_t>(j)] += idt.edge_weight(h) * (mesh.position(i) - mesh.position(j));
  }
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (!mesh.is_boundary_vertex(v)) {
      EXPECT_LT(sum[static_cast<size_t>(v)].norm(), 1e-12) << v;
    }
}

// A sphere with needle triangles: one vertex pushed almost onto an opposite edge of each
// of a few faces. The input has negative cotan weights; the intrinsic triangulation none,
// and its total area and angle sums are the input's (flips change neither).
TEST(IntrinsicTriangulation, NeedlesOnASphere) {
  const Mesh base = make_icosphere(2);
  std::vector<Vec3> p = base.positions();
  for (int f : {0, 17, 40, 101}) {
    const Face& t = base.face(f);
    // Move corner 0 to 97 % of the way onto the midpoint of the opposite edge.
    const Vec3 m = 0.5 * (p[static_cast<size_t>(t[1])] + p[static_cast<size_t>(t[2])]);
    p[static_cast<size_t>(t[0])] += 0.97 * (m - p[static_cast<size_t>(t[0])]);
  }
  const Mesh mesh(std::move(p), base.faces(), "needles");
  const TangentBundle bundle(mesh);
  const IntrinsicTriangulation idt(bundle);
  EXPECT_LT(idt.min_input_weight(), -0.5);
  EXPECT_GT(idt.flips(), 0);
  EXPECT_EQ(idt.clamped_edges(), 0);
  double area = 0, input_area = 0;
  for (int f = 0; f < idt.num_faces(); ++f) area += idt.face_area(f);
  for (int f = 0; f < mesh.num_faces(); ++f) input_area += mesh.face_area(f);
  EXPECT_NEAR(area, input_area, 1e-12 * input_area);
  std::vector<double> angle(static_cast<size_t>(mesh.num_vertices()), 0.0);
  for (int h = 0; h < idt.num_halfedges(); ++h) {
    ASSERT_GE(idt.edge_weight(h), 0.0);
    if (idt.twin(h) >= 0) {
      EXPECT_GE(0.5 * (idt.cot_opposite(h) + idt.cot_opposite(idt.twin(h))), -1e-10);
      EXPECT_EQ(idt.transport(idt.twin(h)), std::conj(idt.transport(h)));
    }
    angle[static_cast<size_t>(idt.tail(h))] += idt.corner_angle(h);
  }
  for (int v = 0; v < mesh.num_vertices(); ++v)
    EXPECT_NEAR(angle[static_cast<size_t>(v)], bundle.angle_sum(v), 1e-10) << v;
}

// Mollification: a face whose corner lies on its opposite edge (zero area in 3D, which
// Mesh accepts only up to rounding) gets every length grown by the least δ that restores
// the margin, and then ordinary flips.
TEST(IntrinsicTriangulation, MollifiesNearlyDegenerateTriangles) {
  const Mesh base = make_icosphere(2);
  std::vector<Vec3> p = base.positions();
  const Face& t = base.face(5);
  const Vec3 m = 0.5 * (p[static_cast<size_t>(t[1])] + p[static_cast<size_t>(t[2])]);
  p[static_cast<size_t>(t[0])] = m + 1e-9 * (p[static_cast<size_t>(t[0])] - m);
  const Mesh mesh(std::move(p), base.faces(), "flat face");
  const TangentBundle bundle(mesh);
  const IntrinsicTriangulation idt(bundle);
  EXPECT_GT(idt.mollification(), 0.0);
  EXPECT_LT(idt.mollification(), 2e-6 * mesh.mean_edge_length());
  for (int h = 0; h < idt.num_halfedges(); ++h) {
    ASSERT_TRUE(std::isfinite(idt.cot_opposite(h))) << h;
    ASSERT_GE(idt.edge_weight(h), 0.0);
  }
}

}  // namespace
}  // namespace tvf
