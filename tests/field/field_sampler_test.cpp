#include "tvf/field/field_sampler.h"

#include "support/test_meshes.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

namespace tvf {
namespace {

using test::grid_mesh;
using test::icosphere_mesh;

// A random point of face f (uniform barycentrics).
SurfacePoint random_point(std::mt19937& rng, int num_faces) {
  std::uniform_int_distribution<int> face(0, num_faces - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double a = u(rng), b = u(rng);
  if (a + b > 1) {
    a = 1 - a;
    b = 1 - b;
  }
  return {face(rng), Vec3(a, b, 1 - a - b)};
}

// z(x, y) = a + b·x + c·y with complex coefficients.
struct Linear {
  cplx a, b, c;
  cplx operator()(const Vec3& p) const { return a + b * p.x() + c * p.y(); }
};

TEST(FieldSampler, PlanarLinearFieldIsReproducedExactly) {
  const Mesh& mesh = grid_mesh();
  const TangentBundle bundle(mesh);
  ASSERT_TRUE(bundle.is_flat());
  const std::vector<Linear> frames = {{{0.3, -0.2}, {1.5, 0.25}, {-0.75, 2.0}},
                                      {{-1.0, 0.5}, {0.2, -1.1}, {0.9, 0.4}},
                                      {{2.0, 2.0}, {-0.6, 0.0}, {0.0, -1.3}}};
  Field field(TimeSampling{0.0, 2.0, 3}, mesh.num_vertices());
  for (int j = 0; j < 3; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) field.at(j, v) = frames[static_cast<size_t>(j)](mesh.position(v));
  const FieldSampler sampler(bundle, field);

  std::mt19937 rng(7);
  for (int k = 0; k < 200; ++k) {
    const SurfacePoint p = random_point(rng, mesh.num_faces());
    const Vec3 x = surface_position(mesh, p);
    for (int j = 0; j < 3; ++j) {
      const cplx expected = frames[static_cast<size_t>(j)](x);
      const double t = field.time().time(j);
      EXPECT_LT(std::abs(sampler.in_face(p, t) - expected), 1e-12) << k << " " << j;
      const Vec3 w = sampler.world(p, t);
      EXPECT_NEAR(w.x(), expected.real(), 1e-12);
      EXPECT_NEAR(w.y(), expected.imag(), 1e-12);
      EXPECT_EQ(w.z(), 0.0);
    }
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    for (int j = 0; j < 3; ++j) {
      const double t = field.time().time(j);
      EXPECT_EQ(sampler.at_vertex(v, t), field.at(j, v));
      EXPECT_LT(std::abs(sampler.at_vertex(v, t) - frames[static_cast<size_t>(j)](mesh.position(v))), 1e-12);
    }
  }
  // Vertices through the faces that hold them: bary = e_k gives the vertex value.
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      SurfacePoint p{f, Vec3::Zero()};
      p.bary[c] = 1.0;
      const int v = mesh.face(f)[static_cast<size_t>(c)];
      EXPECT_EQ(sampler.in_face(p, 1.0), field.at(1, v));
    }
}

TEST(FieldSampler, LinearInTimeBetweenFrames) {
  const Mesh& mesh = grid_mesh();
  const TangentBundle bundle(mesh);
  const Linear f0{{0.3, -0.2}, {1.5, 0.25}, {-0.75, 2.0}};
  const Linear f1{{-1.0, 0.5}, {0.2, -1.1}, {0.9, 0.4}};
  Field field(TimeSampling{1.0, 3.0, 2}, mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    field.at(0, v) = f0(mesh.position(v));
    field.at(1, v) = f1(mesh.position(v));
  }
  const FieldSampler sampler(bundle, field);
  std::mt19937 rng(11);
  for (double s : {0.0, 0.25, 0.6, 1.0}) {
    const double t = 1.0 + 2.0 * s;
    for (int k = 0; k < 50; ++k) {
      const SurfacePoint p = random_point(rng, mesh.num_faces());
      const Vec3 x = surface_position(mesh, p);
      const cplx expected = (1 - s) * f0(x) + s * f1(x);
      EXPECT_LT(std::abs(sampler.in_face(p, t) - expected), 1e-12) << s;
    }
    for (int v = 0; v < mesh.num_vertices(); v += 5)
      EXPECT_LT(std::abs(sampler.at_vertex(v, t) - ((1 - s) * field.at(0, v) + s * field.at(1, v))), 1e-15);
  }
  // Clamped outside the time range.
  EXPECT_EQ(sampler.at_vertex(3, -5.0), field.at(0, 3));
  EXPECT_EQ(sampler.at_vertex(3, 9.0), field.at(1, 3));
}

TEST(FieldSampler, SphereCornersGiveTheTransportedVertexValue) {
  const Mesh& mesh = icosphere_mesh();
  const TangentBundle bundle(mesh);
  Field field(TimeSampling{0.0, 1.0, 4}, mesh.num_vertices());
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const cplx z(g(rng), g(rng));
    for (int j = 0; j < 4; ++j) field.at(j, v) = z;
  }
  const FieldSampler sampler(bundle, field);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      SurfacePoint p{f, Vec3::Zero()};
      p.bary[c] = 1.0;
      const int v = mesh.face(f)[static_cast<size_t>(c)];
      const cplx z = field.at(0, v);
      const cplx expected = bundle.corner_to_face(3 * f + c) * z;
      EXPECT_EQ(sampler.in_face(p, 1.0 / 3), expected);
      EXPECT_LT(std::abs(sampler.in_face(p, 0.5) - expected), 1e-15);
      EXPECT_NEAR(std::abs(sampler.in_face(p, 0.5)), std::abs(z), 1e-14);
      const Vec3 w = sampler.world(p, 0.2);
      EXPECT_NEAR(w.norm(), std::abs(z), 1e-14);
      EXPECT_NEAR(w.dot(bundle.face_normal(f)), 0.0, 1e-14);
    }
}

// Distance from x to triangle (a, b, c), computed independently of closest_point: the
// foot of the perpendicular when it falls inside, else the nearest edge.
double reference_distance(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  const Vec3 q = x - n.dot(x - a) * n;
  const auto side = [&](const Vec3& p0, const Vec3& p1) { return (p1 - p0).cross(q - p0).dot(n); };
  if (side(a, b) >= 0 && side(b, c) >= 0 && side(c, a) >= 0) return (x - q).norm();
  const auto segment = [&](const Vec3& p0, const Vec3& p1) {
    const double s = std::clamp((x - p0).dot(p1 - p0) / (p1 - p0).squaredNorm(), 0.0, 1.0);
    return (x - (p0 + s * (p1 - p0))).norm();
  };
  return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

TEST(ClosestPoint, VertexPositionsReturnThatVertex) {
  for (const Mesh* mesh : {&grid_mesh(), &icosphere_mesh()}) {
    for (int v = 0; v < mesh->num_vertices(); ++v) {
      const SurfacePoint p = closest_point(*mesh, mesh->position(v));
      ASSERT_GE(p.face, 0);
      const Face& f = mesh->face(p.face);
      const auto it = std::find(f.begin(), f.end(), v);
      ASSERT_NE(it, f.end()) << v;
      const auto k = static_cast<int>(it - f.begin());
      for (int c = 0; c < 3; ++c) EXPECT_EQ(p.bary[c], c == k ? 1.0 : 0.0) << v;
      EXPECT_EQ(surface_position(*mesh, p), mesh->position(v));
    }
  }
}

TEST(ClosestPoint, PointsOffTheSphereMatchBruteForce) {
  const Mesh& mesh = icosphere_mesh();
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> radius(0.3, 1.8);
  for (int k = 0; k < 200; ++k) {
    Vec3 x(g(rng), g(rng), g(rng));
    x *= radius(rng) / x.norm();
    const SurfacePoint p = closest_point(mesh, x);
    ASSERT_GE(p.face, 0);
    EXPECT_NEAR(p.bary.sum(), 1.0, 1e-15);
    EXPECT_GE(p.bary.minCoeff(), 0.0);
    double best = std::numeric_limits<double>::infinity();
    for (int f = 0; f < mesh.num_faces(); ++f) {
      const Face& t = mesh.face(f);
      best = std::min(best, reference_distance(x, mesh.position(t[0]), mesh.position(t[1]),
                                               mesh.position(t[2])));
    }
    const Face& t = mesh.face(p.face);
    EXPECT_NEAR((surface_position(mesh, p) - x).norm(), best, 1e-12) << k;
    EXPECT_NEAR(reference_distance(x, mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])),
                best, 1e-12)
        << k;
  }
}

TEST(ClosestPoint, PlanarPointsProjectOntoTheGrid) {
  const Mesh& mesh = grid_mesh();  // [-1, 2] × [-0.5, 1]
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> ux(-1.0, 2.0), uy(-0.5, 1.0), uz(-1.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    const Vec3 x(ux(rng), uy(rng), uz(rng));
    const Vec3 q = surface_position(mesh, closest_point(mesh, x));
    EXPECT_NEAR(q.x(), x.x(), 1e-14);
    EXPECT_NEAR(q.y(), x.y(), 1e-14);
    EXPECT_EQ(q.z(), 0.0);
  }
  // Outside the domain: clamped to the boundary.
  const Vec3 q = surface_position(mesh, closest_point(mesh, Vec3(3.0, 0.25, 0.5)));
  EXPECT_NEAR(q.x(), 2.0, 1e-14);
  EXPECT_NEAR(q.y(), 0.25, 1e-14);
}

}  // namespace
}  // namespace tvf
