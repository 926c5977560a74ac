#include "tvf/integrate/streamline.h"

#include "tvf/core/error.h"
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
  EXPECT_LT(s.points.back().norm(), 0.05);
}

TEST(Streamline, RefusesSurfacesAndSeedsOutside) {
  const Mesh sphere = make_icosphere(1);
  const TangentBundle bs(sphere);
  std::vector<cplx> v(static_cast<size_t>(sphere.num_vertices()), cplx(1, 0));
  EXPECT_THROW(trace_streamline(bs, v, Vec3(1, 0, 0)), Error);
  const Mesh grid = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  const TangentBundle bg(grid);
  std::vector<cplx> w(25, cplx(1, 0));
  EXPECT_THROW(trace_streamline(bg, w, Vec3(3, 0, 0)), Error);
}

}  // namespace
}  // namespace tvf
