#include "tvf/integrate/surface_path.h"

#include "support/test_meshes.h"

#include <gtest/gtest.h>

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
  const std::vector<Vec3> x = paths.between(p, q);
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

}  // namespace
}  // namespace tvf
