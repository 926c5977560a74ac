#include "tvf/integrate/streamline.h"

#include "tvf/core/error.h"
#include "tvf/integrate/surface_walk.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

namespace tvf {
namespace {

TEST(Streamline, OfACenterClosesOnItself) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const cplx p(0.1, -0.05);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()));
  for (int v = 0; v < grid.num_vertices(); ++v)
    values[static_cast<size_t>(v)] = cplx(0, 1) * (cplx(grid.position(v).x(), grid.position(v).y()) - p);
  const Vec3 seed(0.1 + 0.4, -0.05, 0);
  const Streamline s = trace_streamline(bundle, values, seed);
  ASSERT_GT(s.points.size(), 50u);
  double len = 0;
  for (size_t k = 0; k < s.points.size(); ++k) {
    EXPECT_NEAR(std::abs(cplx(s.points[k].x(), s.points[k].y()) - p), 0.4, 1e-6) << k;
    if (k > 0) len += (s.points[k] - s.points[k - 1]).norm();
  }
  // It stopped after one turn: about 2π·0.4 of arc.
  EXPECT_NEAR(len, 2 * kPi * 0.4, 0.05);
}

TEST(Streamline, OfAUniformFieldIsAStraightChord) {
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()), cplx(2, 1));
  const Streamline s = trace_streamline(bundle, values, Vec3(0, 0, 0));
  for (const Vec3& x : s.points) EXPECT_NEAR(x.y() - 0.5 * x.x(), 0.0, 1e-12);
  // From the seed to within a step of the boundary both ways: x from −1 to 1 (|y| ≤ 0.5).
  const double step = 0.5 * grid.mean_edge_length();
  EXPECT_LT(s.points.front().x(), -1 + step);
  EXPECT_GT(s.points.back().x(), 1 - step);
  EXPECT_EQ(s.points[s.seed], Vec3(0, 0, 0));
  // Ordered along the flow: x increases.
  for (size_t k = 1; k < s.points.size(); ++k) EXPECT_GT(s.points[k].x(), s.points[k - 1].x());
}

TEST(Streamline, StopsAtASink) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()));
  for (int v = 0; v < grid.num_vertices(); ++v) values[static_cast<size_t>(v)] = -cplx(grid.position(v).x(), grid.position(v).y());
  const Streamline s = trace_streamline(bundle, values, Vec3(0.5, 0.5, 0));
  // It stops on entering the face that holds the zero (a grid vertex here): within one
  // cell diagonal of it.
  EXPECT_EQ(s.stop_forward, StopReason::singularity);
  EXPECT_LT(s.points.back().norm(), 0.05 * std::sqrt(2.0) + 1e-9);
}

TEST(Streamline, RefusesSeedsOutsideAPlanarDomain) {
  const Mesh grid = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  const TangentBundle bg(grid);
  std::vector<cplx> w(25, cplx(1, 0));
  EXPECT_THROW(trace_streamline(bg, w, Vec3(3, 0, 0)), Error);
}

TEST(Streamline, StopsAtTheBoundaryAndSaysSo) {
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()), cplx(1, 0));
  const Streamline s = trace_streamline(bundle, values, Vec3(0.3, 0.2, 0));
  EXPECT_EQ(s.stop_forward, StopReason::boundary);
  EXPECT_EQ(s.stop_backward, StopReason::boundary);
  // It ends on the boundary itself (the last step is cut at the edge).
  EXPECT_NEAR(s.points.back().x(), 1.0, 1e-12);
  EXPECT_NEAR(s.points.front().x(), -1.0, 1e-12);
  EXPECT_NEAR(s.length(), 2.0, 1e-9);
}

TEST(Streamline, StopsAtASinkByItsFaceIndex) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const cplx c(0.13, -0.07);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()));
  for (int v = 0; v < grid.num_vertices(); ++v)
    values[static_cast<size_t>(v)] = -(cplx(grid.position(v).x(), grid.position(v).y()) - c);
  const Streamline s = trace_streamline(bundle, values, Vec3(0.6, 0.5, 0));
  EXPECT_EQ(s.stop_forward, StopReason::singularity);
  // Inside the sink's face: within one cell diagonal of the zero.
  EXPECT_LT(std::abs(cplx(s.points.back().x(), s.points.back().y()) - c), 0.05 * std::sqrt(2.0));
  // Without the face test it goes on until the speed threshold, closer still.
  StreamlineOptions o;
  o.stop_at_singular_faces = false;
  o.stop_speed = 1e-3;
  const Streamline t = trace_streamline(bundle, values, Vec3(0.6, 0.5, 0), o);
  EXPECT_EQ(t.stop_forward, StopReason::singularity);
  EXPECT_LT(std::abs(cplx(t.points.back().x(), t.points.back().y()) - c), 0.01);
}

TEST(Streamline, StopsAtMaxLengthAndAtTheCallersTest) {
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()), cplx(0, 1));
  StreamlineOptions o;
  o.max_length = 0.5;
  o.step = 0.01;
  const Streamline s = trace_streamline(bundle, values, Vec3(0, 0, 0), o);
  EXPECT_EQ(s.stop_forward, StopReason::length);
  EXPECT_NEAR(s.points.back().y(), 0.5, 1e-9);
  o.max_length = 0;
  o.accept = [](const Vec3& x) { return x.y() < 0.25; };
  const Streamline t = trace_streamline(bundle, values, Vec3(0, 0, 0), o);
  EXPECT_EQ(t.stop_forward, StopReason::rejected);
  EXPECT_LT(t.points.back().y(), 0.25);
  EXPECT_GT(t.points.back().y(), 0.25 - 0.011);
}

// A caller that traces many lines on one frame gives its largest |V| once
// (StreamlineOptions::max_speed): the lines are those traced without it, bit for bit; a
// largest |V| given is the one used (here one so large that the field is "zero"
// everywhere: the line stops at its seed). Each point's position and speed are those of
// its surface point (the speed is read once a step, for the point and the next step).
TEST(Streamline, TakesTheFramesLargestSpeedFromItsCaller) {
  const Mesh grid = make_grid(GridSpec{31, 31, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()));
  for (int v = 0; v < grid.num_vertices(); ++v) {
    const cplx z(grid.position(v).x(), grid.position(v).y());
    values[static_cast<size_t>(v)] = cplx(-0.2, 1) * (z - cplx(0.1, 0.05)) * (1.0 + std::norm(z));
  }
  const double vmax = max_speed(values);
  double largest = 0;
  for (const cplx& z : values) largest = std::max(largest, std::abs(z));
  EXPECT_NEAR(vmax, largest, 1e-15 * largest);
  StreamlineOptions o;
  o.stop_at_singular_faces = false;
  const Streamline plain = trace_streamline(bundle, values, Vec3(0.7, 0.1, 0), o);
  ASSERT_GT(plain.points.size(), 20u);
  o.max_speed = vmax;
  const Streamline given = trace_streamline(bundle, values, Vec3(0.7, 0.1, 0), o);
  ASSERT_EQ(given.points.size(), plain.points.size());
  EXPECT_EQ(given.seed, plain.seed);
  EXPECT_EQ(given.stop_forward, plain.stop_forward);
  EXPECT_EQ(given.stop_backward, plain.stop_backward);
  for (size_t k = 0; k < plain.points.size(); ++k) {
    EXPECT_EQ(given.points[k], plain.points[k]) << k;
    EXPECT_EQ(given.speeds[k], plain.speeds[k]) << k;
    EXPECT_EQ(plain.points[k], surface_position(grid, plain.where[k])) << k;
    EXPECT_EQ(plain.speeds[k], std::abs(interpolate_in_face(bundle, values, plain.where[k]))) << k;
  }
  o.max_speed = 1e12 * vmax;  // every |V| below 1e-9 of it
  const Streamline stopped = trace_streamline(bundle, values, Vec3(0.7, 0.1, 0), o);
  EXPECT_EQ(stopped.points.size(), 1u);
  EXPECT_EQ(stopped.stop_forward, StopReason::singularity);
}

// The rotation about the z axis, ẑ × x, in each vertex's basis: its streamlines are the
// circles of latitude.
std::vector<cplx> sphere_vortex(const TangentBundle& bundle) {
  const Mesh& m = bundle.mesh();
  std::vector<cplx> values(static_cast<size_t>(m.num_vertices()));
  for (int v = 0; v < m.num_vertices(); ++v)
    values[static_cast<size_t>(v)] = bundle.world_to_vertex(v, Vec3::UnitZ().cross(m.position(v)));
  return values;
}

TEST(Streamline, AroundAVortexOnTheSphereClosesOnTheSurface) {
  const Mesh sphere = make_icosphere(4);
  const TangentBundle bundle(sphere);
  const auto values = sphere_vortex(bundle);
  const Vec3 seed = Vec3(std::cos(0.5), 0, std::sin(0.5));  // latitude 0.5 rad
  StreamlineOptions o;
  o.max_length = 10;  // longer than the circle (the default, the box diagonal, is shorter)
  const Streamline s = trace_streamline(bundle, values, seed, o);
  EXPECT_EQ(s.stop_forward, StopReason::closed);
  const double r = std::cos(0.5);
  ASSERT_GT(s.points.size(), 40u);
  for (size_t k = 0; k < s.points.size(); ++k) {
    const Vec3& x = s.points[k];
    // On the surface: in the plane of its face (the mesh is inscribed in the unit sphere).
    const SurfacePoint& p = s.where[k];
    const Vec3 n = bundle.face_normal(p.face);
    EXPECT_NEAR((x - sphere.position(sphere.face(p.face)[0])).dot(n), 0.0, 1e-12) << k;
    EXPECT_GT(x.norm(), 0.99) << k;
    EXPECT_LE(x.norm(), 1.0 + 1e-12) << k;
    // On its circle of latitude (up to the faceting of the sphere).
    EXPECT_NEAR(x.z(), seed.z(), 0.01) << k;
  }
  // About one turn.
  EXPECT_NEAR(s.length(), 2 * kPi * r, 0.03 * 2 * kPi * r);
}

TEST(Streamline, OnATorusStaysOnTheSurface) {
  const Mesh torus = make_torus(48, 24);
  const TangentBundle bundle(torus);
  // A field that winds around the torus: the rotation about z plus a twist about the tube.
  std::vector<cplx> values(static_cast<size_t>(torus.num_vertices()));
  for (int v = 0; v < torus.num_vertices(); ++v) {
    const Vec3 x = torus.position(v);
    const Vec3 around = Vec3::UnitZ().cross(x);
    const Vec3 tube = bundle.vertex_normal(v).cross(around.normalized());
    values[static_cast<size_t>(v)] = bundle.world_to_vertex(v, around + 0.5 * tube);
  }
  StreamlineOptions o;
  o.max_length = 20;
  const Streamline s = trace_streamline(bundle, values, torus.position(0), o);
  EXPECT_GT(s.length(), 10.0);
  for (size_t k = 0; k < s.points.size(); ++k) {
    const SurfacePoint& p = s.where[k];
    EXPECT_NEAR(p.bary.sum(), 1.0, 1e-12);
    EXPECT_GE(p.bary.minCoeff(), 0.0);
    const Vec3 n = bundle.face_normal(p.face);
    EXPECT_NEAR((s.points[k] - torus.position(torus.face(p.face)[0])).dot(n), 0.0, 1e-12) << k;
    // Distance to the tube's core circle stays about the minor radius.
    const Vec3 x = s.points[k];
    const Vec3 core = Vec3(x.x(), x.y(), 0).normalized();
    EXPECT_NEAR((x - core).norm(), 0.35, 0.01) << k;
  }
}

}  // namespace
}  // namespace tvf
