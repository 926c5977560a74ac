#include "tvf/integrate/surface_path.h"

#include "support/test_meshes.h"
#include "tvf/integrate/surface_walk.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tvf {
namespace {

double length(const std::vector<Vec3>& x) {
  double l = 0;
  for (size_t k = 1; k < x.size(); ++k) l += (x[k] - x[k - 1]).norm();
  return l;
}

TEST(SurfacePaths, OnTheSphereIsAnArcOfAGreatCircle) {
  // (1, 0, 0) to a point 100° round the great circle through it tilted 30° from the equator:
  // the shortest path over the sphere is that arc (length 100° in radians), every point on
  // the plane of the circle and on the sphere, evenly spaced.
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const PointLocator locator(sphere);
  const SurfacePaths paths(bundle, locator);
  const double angle = 100 * std::numbers::pi / 180, tilt = 30 * std::numbers::pi / 180;
  const Vec3 normal(0, -std::sin(tilt), std::cos(tilt));  // the great circle's plane
  const Vec3 p = surface_position(sphere, locator.closest(Vec3(1, 0, 0)));
  const Vec3 q = surface_position(
      sphere, locator.closest(Vec3(std::cos(angle), std::sin(angle) * std::cos(tilt), std::sin(angle) * std::sin(tilt))));
  // The straightened chords, and the route (straightened by walks over the surface).
  for (const std::vector<Vec3>& x : {paths.between(p, q), paths.route(p, q).points}) {
    ASSERT_GT(x.size(), 10u);
    EXPECT_EQ(x.front(), p);
    EXPECT_EQ(x.back(), q);
    const double h = sphere.mean_edge_length();
    EXPECT_NEAR(length(x), angle, 0.02 * angle);
    for (const Vec3& y : x) {
      EXPECT_NEAR(y.norm(), 1.0, 0.02);
      EXPECT_LT(std::abs(y.dot(normal)), 0.3 * h);
    }
    for (size_t k = 2; k < x.size(); ++k)
      EXPECT_NEAR((x[k] - x[k - 1]).norm(), (x[1] - x[0]).norm(), 0.3 * h);
  }
}

TEST(SurfacePaths, NoneBetweenSeparatePiecesAndTheEndsWhenTheyAreOnePoint) {
  const Mesh squares({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 10}, {1, 0, 10}, {1, 1, 10}, {0, 1, 10}},
                     {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}});
  const TangentBundle bundle(squares);
  const PointLocator locator(squares);
  const SurfacePaths paths(bundle, locator);
  EXPECT_TRUE(paths.between(Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 10)).empty());
  const std::vector<Vec3> one = paths.between(Vec3(0.5, 0.2, 0), Vec3(0.5, 0.2, 0));
  ASSERT_EQ(one.size(), 2u);
  EXPECT_EQ(one[0], one[1]);
  // Within one square: the straight segment.
  const std::vector<Vec3> flat = paths.between(Vec3(0.1, 0.2, 10), Vec3(0.9, 0.7, 10));
  EXPECT_NEAR(length(flat), (Vec3(0.8, 0.5, 0)).norm(), 1e-6);
}

TEST(SurfacePaths, ARouteGoesOverTheRimOfAThinPartAndEveryStepIsAWalkToTheNextPoint) {
  // From the top of a slab a fiftieth of an edge length thick to the point under it on the
  // bottom, a quarter from the rim: the shortest path over the surface runs to the rim,
  // over it and back (0.5 and the thickness). Straightening the chords (between) draws it
  // through the slab instead, 0.04 long (its points on either side, the chord's closest
  // surface points jumping from one sheet to the other); the route may not: walking each step
  // from its start ends at the next point, so every point between is on the surface and
  // continuous along it, and the route is the path over the rim.
  const Mesh& mesh = test::slab_mesh();
  const double thickness = test::kSlabThickness;
  const TangentBundle bundle(mesh);
  const PointLocator locator(mesh);
  const SurfacePaths paths(bundle, locator);
  const Vec3 p(0.75, 0.52, thickness), q(0.75, 0.48, 0);
  const SurfacePaths::Route route = paths.route(p, q);
  ASSERT_GE(route.points.size(), 3u);
  ASSERT_EQ(route.starts.size(), route.points.size() - 1);
  ASSERT_EQ(route.steps.size(), route.points.size() - 1);
  EXPECT_EQ(route.points.front(), p);
  EXPECT_EQ(route.points.back(), q);
  const double h = mesh.mean_edge_length();
  double rim = 0;
  for (size_t k = 0; k + 1 < route.points.size(); ++k) {
    EXPECT_NEAR((surface_position(mesh, route.starts[k]) - route.points[k]).norm(), 0.0, 1e-9) << k;
    const SurfacePoint end = walk_surface(bundle, route.starts[k], route.steps[k]).end;
    EXPECT_NEAR((surface_position(mesh, end) - route.points[k + 1]).norm(), 0.0, 1e-5 * h) << k;
    rim = std::max(rim, route.points[k].x());
  }
  EXPECT_NEAR(rim, 1.0, 1e-9);
  const double over_the_rim = std::hypot(0.5 + thickness, 0.04);
  EXPECT_GE(length(route.points), over_the_rim - 1e-6);
  EXPECT_LE(length(route.points), over_the_rim + 1e-3);
}

TEST(SurfacePaths, ARouteAlongTheBoundaryWalksAlongIt) {
  // Between two points of a hemisphere's rim a quarter round it: the shortest path runs
  // along the rim (a quarter of the equator, less or more the rim's zigzag between the
  // icosphere's faces), and each step walks to the next point without stopping on the
  // boundary it runs beside.
  const Mesh& mesh = test::hemisphere_mesh();
  const TangentBundle bundle(mesh);
  const PointLocator locator(mesh);
  const SurfacePaths paths(bundle, locator);
  const Vec3 p = surface_position(mesh, locator.closest(Vec3(1, 0, 0)));
  const Vec3 q = surface_position(mesh, locator.closest(Vec3(0, 1, 0)));
  const SurfacePaths::Route route = paths.route(p, q);
  ASSERT_GE(route.points.size(), 3u);
  for (size_t k = 0; k + 1 < route.points.size(); ++k) {
    const SurfaceWalk walk = walk_surface(bundle, route.starts[k], route.steps[k]);
    EXPECT_NEAR((surface_position(mesh, walk.end) - route.points[k + 1]).norm(), 0.0, 1e-9) << k;
  }
  EXPECT_NEAR(length(route.points), std::numbers::pi / 2, 0.03 * std::numbers::pi / 2);
}

}  // namespace
}  // namespace tvf
