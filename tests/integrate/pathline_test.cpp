#include "tvf/integrate/pathline.h"

#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <limits>

namespace tvf {
namespace {

Field constant_field(const Mesh& mesh, TimeSampling time, cplx value) {
  Field f(time, mesh.num_vertices());
  for (auto& z : f.data()) z = value;
  return f;
}

TEST(Pathline, OfAUniformFieldIsStraightWithTheRightLength) {
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const cplx v(0.6, -0.3);
  const Field field = constant_field(grid, TimeSampling{0, 1, 11}, v);
  const Vec3 seed(-0.4, 0.2, 0);
  const Pathline p = trace_pathline(bundle, field, seed);
  EXPECT_EQ(p.stop, StopReason::time_range);
  EXPECT_DOUBLE_EQ(p.times.front(), 0.0);
  EXPECT_DOUBLE_EQ(p.times.back(), 1.0);
  for (size_t k = 0; k < p.points.size(); ++k) {
    const Vec3 expect = seed + p.times[k] * Vec3(v.real(), v.imag(), 0);
    EXPECT_NEAR((p.points[k] - expect).norm(), 0.0, 1e-12) << k;
  }
  EXPECT_NEAR(p.length(), std::abs(v), 1e-12);
}

TEST(Pathline, RefusesAStepThatIsNegativeOrTakesOverAMillionSteps) {
  // 1e-12 over [0, 1]: 1e12 steps, each point kept (80 TB); refused at once, naming the step.
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = constant_field(grid, TimeSampling{0, 1, 5}, cplx(0.1, 0));
  PathlineOptions o;
  o.dt = 1e-12;
  try {
    trace_pathline(bundle, field, Vec3(0, 0, 0), o);
    ADD_FAILURE() << "not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pathline time step 1e-12 would take 1e+12 RK4 steps"), std::string::npos)
        << e.what();
  }
  o.dt = -0.1;
  EXPECT_THROW(trace_pathline(bundle, field, Vec3(0, 0, 0), o), Error);
  o.dt = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(trace_pathline(bundle, field, Vec3(0, 0, 0), o), Error);
  // Exactly a million steps is allowed (and the last point is at t_end).
  o.dt = 1e-6;
  o.t_end = 1;
  o.stop_speed = 0;
  EXPECT_DOUBLE_EQ(trace_pathline(bundle, field, Vec3(-0.9, 0, 0), o).times.back(), 1.0);
}

TEST(Pathline, BackwardsInTimeAndPartOfTheRange) {
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = constant_field(grid, TimeSampling{0, 2, 5}, cplx(0.5, 0));
  PathlineOptions o;
  o.t_start = 1.5;
  o.t_end = 0.5;
  const Pathline p = trace_pathline(bundle, field, Vec3(0, 0, 0), o);
  EXPECT_NEAR(p.points.back().x(), -0.5, 1e-12);
  EXPECT_DOUBLE_EQ(p.times.back(), 0.5);
  o.t_end = 3;
  EXPECT_THROW(trace_pathline(bundle, field, Vec3(0, 0, 0), o), Error);
}

TEST(Pathline, FollowsTheFieldInterpolatedLinearlyInTime) {
  // V(t) = (t, 0) on frames 0 and 1 only: x(t) = x0 + t²/2 exactly for linear-in-time
  // interpolation, which RK4 integrates exactly.
  const Mesh grid = make_grid(GridSpec{11, 11, {-2, -2}, {2, 2}});
  const TangentBundle bundle(grid);
  Field field(TimeSampling{0, 1, 2}, grid.num_vertices());
  for (int v = 0; v < grid.num_vertices(); ++v) {
    field.at(0, v) = 0;
    field.at(1, v) = cplx(1, 0);
  }
  PathlineOptions o;
  o.dt = 0.1;
  o.stop_speed = 0;
  o.stop_at_singular_faces = false;
  const Pathline p = trace_pathline(bundle, field, Vec3(0.1, 0.3, 0), o);
  for (size_t k = 0; k < p.points.size(); ++k)
    EXPECT_NEAR(p.points[k].x(), 0.1 + 0.5 * p.times[k] * p.times[k], 1e-12) << k;
}

TEST(Pathline, StopsAtTheBoundaryAndAtMaxLength) {
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = constant_field(grid, TimeSampling{0, 1, 3}, cplx(4, 0));
  const Pathline p = trace_pathline(bundle, field, Vec3(0, 0, 0));
  EXPECT_EQ(p.stop, StopReason::boundary);
  EXPECT_NEAR(p.points.back().x(), 1.0, 1e-12);
  EXPECT_NEAR(p.times.back(), 0.25, 1e-12);  // reached x = 1 at t = 1/4
  PathlineOptions o;
  o.max_length = 0.5;
  const Pathline q = trace_pathline(bundle, field, Vec3(0, 0, 0), o);
  EXPECT_EQ(q.stop, StopReason::length);
  EXPECT_GE(q.length(), 0.5);
  EXPECT_LT(q.length(), 0.5 + 4 * 0.25 / 2 + 1e-12);  // at most one step more
}

TEST(Pathline, AroundAVortexOnTheSphereStaysOnItsLatitude) {
  const Mesh sphere = make_icosphere(4);
  const TangentBundle bundle(sphere);
  Field field(TimeSampling{0, 1, 3}, sphere.num_vertices());
  for (int j = 0; j < 3; ++j)
    for (int v = 0; v < sphere.num_vertices(); ++v)
      field.at(j, v) = bundle.world_to_vertex(v, 2 * kPi * Vec3::UnitZ().cross(sphere.position(v)));
  const Vec3 seed(std::cos(0.3), 0, std::sin(0.3));
  PathlineOptions o;
  o.dt = 0.005;
  const Pathline p = trace_pathline(bundle, field, seed, o);
  EXPECT_EQ(p.stop, StopReason::time_range);
  for (const Vec3& x : p.points) {
    EXPECT_NEAR(x.z(), seed.z(), 0.01);
    EXPECT_GT(x.norm(), 0.99);
  }
  // Angular speed 2π: one turn in unit time, back near the seed.
  EXPECT_LT((p.points.back() - seed).norm(), 0.05);
}

}  // namespace
}  // namespace tvf
