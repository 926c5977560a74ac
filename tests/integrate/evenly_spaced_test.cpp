#include "tvf/integrate/evenly_spaced.h"

#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

namespace tvf {
namespace {

TEST(EvenlySpaced, LinesOfAUniformFieldAreParallelAtTheSeparation) {
  const Mesh grid = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()), cplx(1, 0));
  EvenlySpacedOptions o;
  o.separation = 0.1;
  const auto lines = evenly_spaced_streamlines(bundle, values, o);
  // Horizontal lines 0.1 apart across [-1, 1]: about 21 of them.
  ASSERT_GE(lines.size(), 19u);
  ASSERT_LE(lines.size(), 21u);
  std::vector<double> ys;
  for (const auto& l : lines) {
    for (const Vec3& x : l.points) EXPECT_NEAR(x.y(), l.points.front().y(), 1e-12);
    ys.push_back(l.points.front().y());
  }
  std::sort(ys.begin(), ys.end());
  for (size_t k = 1; k < ys.size(); ++k) EXPECT_NEAR(ys[k] - ys[k - 1], 0.1, 1e-9);
}

TEST(EvenlySpaced, NoTwoLinesComeCloserThanTheTestDistance) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  std::vector<cplx> values(static_cast<size_t>(grid.num_vertices()));
  for (int v = 0; v < grid.num_vertices(); ++v) {
    const cplx x(grid.position(v).x(), grid.position(v).y());
    values[static_cast<size_t>(v)] = cplx(0, 1) * (x - 0.3) + 0.3 * x;  // a repelling focus
  }
  EvenlySpacedOptions o;
  o.separation = 0.08;
  const auto lines = evenly_spaced_streamlines(bundle, values, o);
  ASSERT_GT(lines.size(), 10u);
  for (size_t a = 0; a < lines.size(); ++a)
    for (size_t b = a + 1; b < lines.size(); ++b)
      for (const Vec3& x : lines[a].points)
        for (const Vec3& y : lines[b].points) ASSERT_GE((x - y).norm(), 0.5 * 0.08 - 1e-12) << a << " " << b;
}

TEST(EvenlySpaced, RefusesSurfaces) {
  const Mesh sphere = make_icosphere(1);
  const TangentBundle bundle(sphere);
  std::vector<cplx> values(static_cast<size_t>(sphere.num_vertices()), cplx(1, 0));
  EXPECT_THROW(evenly_spaced_streamlines(bundle, values), Error);
}

}  // namespace
}  // namespace tvf
