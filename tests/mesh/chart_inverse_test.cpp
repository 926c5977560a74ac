#include "tvf/mesh/chart_inverse.h"

#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tvf {
namespace {

TEST(ChartInverse, IsTranslationOnAPlane) {
  const Mesh grid = make_grid(GridSpec{21, 11, {-1, -0.5}, {3, 1.5}});
  const TangentBundle bundle(grid);
  const LogMap log(bundle);
  const SurfacePoint p{7, Vec3(0.2, 0.3, 0.5)};
  const Vec3 x = surface_position(grid, p);
  LocalChart chart;
  log.compute(p, chart);
  const ChartInverse inverse(bundle, chart, 10.0);
  ASSERT_GT(x.x(), -0.9);
  ASSERT_LT(x.y(), 0.0);
  for (const cplx w : {cplx(0.3, 0.2), cplx(-0.123, 0.456), cplx(1.5, 1.25)}) {
    const auto q = inverse.locate(w);
    ASSERT_TRUE(q);
    const Vec3 y = surface_position(grid, *q);
    EXPECT_NEAR(y.x(), x.x() + w.real(), 1e-12);
    EXPECT_NEAR(y.y(), x.y() + w.imag(), 1e-12);
    EXPECT_NEAR(std::abs(inverse.coords(*q) - w), 0.0, 1e-12);
    EXPECT_NEAR(std::abs(inverse.frame_in_face(*q) - cplx(1, 0)), 0.0, 1e-12);
  }
  // Outside the domain there is no inverse.
  EXPECT_FALSE(inverse.locate(cplx(-5, 0)));
}

// On the unit sphere the inverse is the exponential map: the point at geodesic distance r
// in direction φ (against the chart's frame at p) lies at angle r from p, and going back
// through the chart gives the same coordinates.
TEST(ChartInverse, IsTheExponentialMapOnTheSphere) {
  const Mesh sphere = make_icosphere(5);
  const TangentBundle bundle(sphere);
  const LogMap log(bundle);
  const SurfacePoint p{2345, Vec3(0.2, 0.5, 0.3)};
  const Vec3 pn = surface_position(sphere, p).normalized();
  LocalChart chart;
  log.compute(p, chart);
  const ChartInverse inverse(bundle, chart, 1.5);
  const Vec3 e1 = bundle.face_e1(p.face), e2 = bundle.face_e2(p.face);
  const double h = sphere.mean_edge_length();
  double worst_r = 0, worst_dir = 0;
  for (double r : {0.1, 0.3, 0.6, 1.0})
    for (int k = 0; k < 12; ++k) {
      const double phi = 2 * M_PI * k / 12;
      const cplx w = std::polar(r, phi);
      const auto q = inverse.locate(w);
      ASSERT_TRUE(q) << r << " " << phi;
      const Vec3 y = surface_position(sphere, *q).normalized();
      worst_r = std::max(worst_r, std::abs(std::acos(std::clamp(pn.dot(y), -1.0, 1.0)) - r));
      const Vec3 u = (y - pn.dot(y) * pn).normalized();  // the geodesic's direction at p
      worst_dir = std::max(worst_dir, std::abs(std::arg(cplx(u.dot(e1), u.dot(e2)) / w)));
      EXPECT_LT(std::abs(inverse.coords(*q) - w), 1e-9);
    }
  // The log map's own accuracy (tests/mesh/log_map_test.cpp): distance within an edge,
  // direction within a few degrees.
  EXPECT_LT(worst_r, h) << worst_r;
  EXPECT_LT(worst_dir, 0.06) << worst_dir;
  // Beyond the radius: no inverse.
  EXPECT_FALSE(inverse.locate(cplx(1.6, 0)));
}

}  // namespace
}  // namespace tvf
