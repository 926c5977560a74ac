#include "tvf/integrate/flow_map.h"

#include "support/test_fields.h"
#include "support/test_meshes.h"
#include "tvf/core/error.h"
#include "tvf/field/point_locator.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tvf {
namespace {

using test::field_from;

SurfacePoint at(const Mesh& mesh, const Vec3& x) { return PointLocator(mesh).closest(x); }

TEST(FlowMap, CarriesAUniformFieldExactlyAndReportsWhereItLeaves) {
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3&, double) { return Vec3(0.6, -0.2, 0); });
  const FlowMap flow(bundle, field);
  const FlowMapResult r = flow.advect(at(grid, Vec3(-0.5, 0.3, 0)), 0.25, 1.25);
  EXPECT_FALSE(r.left);
  EXPECT_NEAR((surface_position(grid, r.where) - Vec3(0.1, 0.1, 0)).norm(), 0.0, 1e-9);
  // Backwards in time: the other way.
  const FlowMapResult b = flow.advect(at(grid, Vec3(0.1, 0.1, 0)), 1.25, 0.25);
  EXPECT_NEAR((surface_position(grid, b.where) - Vec3(-0.5, 0.3, 0)).norm(), 0.0, 1e-9);
  // From x = 0.5 the particle reaches x = 1 at t = 0.5/0.6 ≈ 0.83: it leaves in the step
  // that crosses (steps of a quarter frame, 0.125).
  const FlowMapResult out = flow.advect(at(grid, Vec3(0.5, 0, 0)), 0, 2);
  EXPECT_TRUE(out.left);
  EXPECT_NEAR(out.t_left, 0.5 / 0.6, 0.125 + 1e-9);
  EXPECT_NEAR(surface_position(grid, out.where).x(), 1.0, 1e-9);
  EXPECT_THROW(flow.advect(at(grid, Vec3(0, 0, 0)), 0, 2.5), Error);
}

TEST(FlowMap, SlidesAlongTheBoundaryWhereTheFlowIsTangential) {
  // V = (1, 0): a particle on the bottom edge y = −1 moves along it and stays in.
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3&, double) { return Vec3(1, 0, 0); });
  const FlowMap flow(bundle, field);
  for (const double x0 : {-0.9, -0.5, -0.33}) {
    const FlowMapResult r = flow.advect(at(grid, Vec3(x0, -1, 0)), 0, 1);
    EXPECT_FALSE(r.left) << x0;
    EXPECT_NEAR((surface_position(grid, r.where) - Vec3(x0 + 1, -1, 0)).norm(), 0.0, 1e-6) << x0;
  }
}

TEST(FlowMap, RotatesWithASteadyRotationAndFollowsTimeInterpolation) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // V = ω(−y, x) with ω = 1 + t: the angle turned from 0 to 1 is ∫(1 + t) dt = 1.5 (the
  // field is linear in t between frames, so the interpolation is exact).
  const Field field = field_from(bundle, TimeSampling{0, 1, 6},
                                 [](const Vec3& x, double t) -> Vec3 { return (1 + t) * Vec3(-x.y(), x.x(), 0); });
  const FlowMap flow(bundle, field, FlowMapOptions{0.01});
  const FlowMapResult r = flow.advect(at(grid, Vec3(0.6, 0, 0)), 0, 1);
  ASSERT_FALSE(r.left);
  EXPECT_NEAR((surface_position(grid, r.where) - Vec3(0.6 * std::cos(1.5), 0.6 * std::sin(1.5), 0)).norm(), 0.0, 1e-8);
}

TEST(FlowMap, StaysOnTheSphere) {
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  const FlowMap flow(bundle, field);
  const Vec3 p(0.6, 0, 0.8);
  const FlowMapResult r = flow.advect(at(sphere, p), 0, 1);
  const Vec3 q = surface_position(sphere, r.where);
  // Rotation by 1 radian about z: the height is kept and the angle within the mesh's error.
  EXPECT_NEAR(q.z(), 0.8, 0.02);
  EXPECT_NEAR(std::atan2(q.y(), q.x()), 1.0, 0.03);
}

TEST(FlowMap, StepsAtMostAnEdgeAtTheFastestPointAndRefusesAFieldFarTooFast) {
  // ω = 40 over [0, 1] with 5 frames: a step of half a frame (0.125) would turn a particle
  // at radius 0.6 by 5 radians, 3 units along the circle; RK4 in one such step misses the
  // circle by far (and the walk would cross about a hundred faces). With steps of at most
  // four mean edge lengths at the fastest point (the corners, ω√2) the particle turns by
  // 40 radians and stays on its circle, on the grid's fast path and on the walk alike.
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  static constexpr double kOmega = 40;
  const Field field = field_from(bundle, TimeSampling{0, 1, 5},
                                 [](const Vec3& x, double) -> Vec3 { return kOmega * Vec3(-x.y(), x.x(), 0); });
  const Vec3 want(0.6 * std::cos(kOmega), 0.6 * std::sin(kOmega), 0);
  for (const bool walk : {false, true}) {
    FlowMapOptions o;
    o.walk = walk;
    const FlowMap flow(bundle, field, o);
    EXPECT_EQ(flow.on_grid(), !walk);
    EXPECT_NEAR(flow.dt(), FlowMap::kReachEdges * grid.mean_edge_length() / (kOmega * std::sqrt(2.0)), 1e-9);
    const FlowMapResult r = flow.advect(at(grid, Vec3(0.6, 0, 0)), 0, 1);
    ASSERT_FALSE(r.left) << walk;
    EXPECT_NEAR((surface_position(grid, r.where) - want).norm(), 0.0, 1e-3) << walk;
  }
  // A slower field (1.4 at the corners: 0.18 per step, under four edges of 0.057) keeps
  // its step.
  const Field slow = field_from(bundle, TimeSampling{0, 1, 5},
                                [](const Vec3& x, double) -> Vec3 { return Vec3(-x.y(), x.x(), 0); });
  EXPECT_DOUBLE_EQ(FlowMap(bundle, slow).dt(), 0.125);

  // A field crossing millions of edges per frame: refused in one sentence, not walked.
  const Field fast = field_from(bundle, TimeSampling{0, 1, 5},
                                [](const Vec3& x, double) -> Vec3 { return 1e8 * Vec3(-x.y(), x.x(), 0); });
  try {
    const FlowMap flow(bundle, fast);
    ADD_FAILURE() << "not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("too fast for its time range"), std::string::npos) << e.what();
  }
}

TEST(FlowMap, RefusesAGivenStepThatWouldTakeOverAMillionStepsAcrossTheTimeRange) {
  // [0, 1] in steps of 1e-12 is 1e12 RK4 steps per particle: a command that never ends,
  // refused at once, naming the step and the least one allowed. 1e-6 is exactly the bound.
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3&, double) { return Vec3(0.1, 0, 0); });
  FlowMapOptions o;
  o.dt = 1e-12;
  try {
    const FlowMap flow(bundle, field, o);
    ADD_FAILURE() << "not refused";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("time step 1e-12"), std::string::npos) << what;
    EXPECT_NE(what.find("at least 1e-06"), std::string::npos) << what;
  }
  o.dt = 1e-6;
  EXPECT_DOUBLE_EQ(FlowMap(bundle, field, o).dt(), 1e-6);
}

}  // namespace
}  // namespace tvf
