#include "tvf/integrate/surface_walk.h"

#include "tvf/mesh/grid.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"
#include "support/test_paths.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>

namespace tvf {
namespace {

TEST(SurfaceWalk, OnAPlaneIsTheStraightSegment) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Vec3 x0(-0.61, -0.33, 0);
  const SurfacePoint p = closest_point(grid, x0);
  const SurfaceWalk w = walk_surface(bundle, p, cplx(1.1, 0.9));
  EXPECT_FALSE(w.hit_boundary);
  EXPECT_EQ(w.transport, cplx(1, 0));
  EXPECT_NEAR((surface_position(grid, w.end) - Vec3(0.49, 0.57, 0)).norm(), 0, 1e-12);
  // Cut at the boundary, with the fraction walked.
  const SurfaceWalk b = walk_surface(bundle, p, cplx(4, 0));
  EXPECT_TRUE(b.hit_boundary);
  EXPECT_NEAR(surface_position(grid, b.end).x(), 1.0, 1e-12);
  EXPECT_NEAR(b.travelled, (1.0 + 0.61) / 4, 1e-12);
}

TEST(SurfaceWalk, WalkingBackReturnsToTheStartOnACurvedSurface) {
  const Mesh sphere = make_icosphere(3);
  const TangentBundle bundle(sphere);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 50; ++k) {
    SurfacePoint p;
    p.face = static_cast<int>((k * 37) % sphere.num_faces());
    p.bary = Vec3(0.2 + 0.3 * std::abs(u(rng)), 0.3, 0.3);
    p.bary /= p.bary.sum();
    const cplx d(0.4 * u(rng), 0.4 * u(rng));
    const SurfaceWalk there = walk_surface(bundle, p, d);
    EXPECT_NEAR(std::abs(there.transport), 1.0, 1e-12);
    // The displacement carried to the end face, reversed, leads back.
    const SurfaceWalk back = walk_surface(bundle, there.end, -d * there.transport);
    EXPECT_NEAR((surface_position(sphere, back.end) - surface_position(sphere, p)).norm(), 0.0, 1e-9) << k;
    // Every point stays on its face's plane: on the surface.
    const Vec3 x = surface_position(sphere, there.end);
    EXPECT_LE(x.norm(), 1.0 + 1e-12);
    EXPECT_GT(x.norm(), 0.95);
  }
}

TEST(SurfaceWalk, StopsOnEnteringANamedFace) {
  const Mesh grid = make_grid(GridSpec{5, 5, {0, 0}, {4, 4}});  // unit cells
  const TangentBundle bundle(grid);
  const SurfacePoint p = closest_point(grid, Vec3(0.5, 0.25, 0));
  const SurfacePoint target = closest_point(grid, Vec3(2.5, 0.25, 0));
  const SurfaceWalk w = walk_surface(bundle, p, cplx(3, 0), [&](int f) { return f == target.face; });
  EXPECT_TRUE(w.stopped);
  EXPECT_EQ(w.end.face, target.face);
  const Vec3 x = surface_position(grid, w.end);
  EXPECT_NEAR(x.y(), 0.25, 1e-12);
  EXPECT_GT(x.x(), 2.0 - 1e-12);  // entered the cell [2, 3]
  EXPECT_LT(x.x(), 2.5);
}

// A walk that starts on an edge (a corner's coordinate 2⁻⁵³) by a displacement of 1e-18
// across it: each face's rounding sent it into the other, for ever (the check "did not end"
// failed: a key-frame knot on CGAL's cow, a curve point straightened onto an edge). It stays
// on the edge now, where it started to rounding.
TEST(SurfaceWalk, AWalkAlongAnEdgeByLessThanRoundingEnds) {
  const test::TempDir dir;
  const std::optional<std::filesystem::path> cow_off = test::cgal_mesh(dir, "cow");
  if (!cow_off)
    GTEST_SKIP() << test::kCgalArchive << " is missing or has no data/meshes/cow.off (Debian package libcgal-demo)";
  const Mesh cow = load_mesh(cow_off->string()).mesh;
  ASSERT_GT(cow.num_faces(), 3762);
  const TangentBundle bundle(cow);
  SurfacePoint p;
  p.face = 3762;
  p.bary = Vec3(0x1p-53, 0x1.0e70533cd574dp-1, 0x1.e31f598655164p-2);
  const SurfaceWalk w = walk_surface(bundle, p, cplx(0x1.9cdae9fae3dcp-59, 0x1.8c09ffb81009p-58));
  EXPECT_FALSE(w.hit_boundary);
  EXPECT_LT((surface_position(cow, w.end) - surface_position(cow, p)).norm(), 1e-15);
}

}  // namespace
}  // namespace tvf
