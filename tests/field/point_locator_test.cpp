#include "tvf/field/point_locator.h"

#include "tvf/core/types.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace tvf {
namespace {

// A disc of n triangles around vertex 0, each listed starting from the centre: every
// triangle's first corner is the same point.
Mesh fan_disc(int n) {
  std::vector<Vec3> positions{Vec3::Zero()};
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi * k / n;
    positions.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  std::vector<Face> faces;
  for (int k = 0; k < n; ++k) faces.push_back({0, 1 + k, 1 + (k + 1) % n});
  return Mesh(std::move(positions), std::move(faces), "fan");
}

Vec3 position_of(const Mesh& mesh, const SurfacePoint& p) {
  const Face& f = mesh.face(p.face);
  return p.bary[0] * mesh.position(f[0]) + p.bary[1] * mesh.position(f[1]) + p.bary[2] * mesh.position(f[2]);
}

// Issue 17 item 3: CGAL's distance accelerator built a kd-tree over the triangles' first
// corners, here 60,000 copies of the centre, and recursed once per triangle (a stack
// overflow). The locator must build on such a mesh and answer exactly.
TEST(PointLocator, FanWhoseTrianglesShareTheirFirstCornerLocatesExactly) {
  constexpr int n = 60'000;
  const Mesh mesh = fan_disc(n);
  const PointLocator locator(mesh);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  for (int i = 0; i < 200; ++i) {
    const Vec3 x(u(rng), u(rng), 0.5 * u(rng));
    const SurfacePoint p = locator.closest(x);
    ASSERT_GE(p.face, 0);
    ASSERT_LT(p.face, n);
    // The closest point of the disc (up to the polygon's chords) is x's projection,
    // pulled onto the unit circle when outside it; its angle names the face.
    Vec3 q(x.x(), x.y(), 0.0);
    const double r = q.norm();
    const Vec3 found = position_of(mesh, p);
    // The triangles are slivers 1e-4 wide: CGAL's point–triangle distance in doubles may
    // pick a neighbour whose closest point is a few 1e-9 away, and off the plane such
    // squared distances tie. Within 1e-7, and within two faces of the angle's face.
    if (r < 0.99) {
      EXPECT_NEAR((found - q).norm(), 0.0, 1e-7) << i;
    } else {
      EXPECT_NEAR(found.norm(), std::min(r, 1.0), 1e-7) << i;
    }
    if (r < 0.99) {
      const SurfacePoint in_plane = locator.closest(q);
      EXPECT_NEAR((position_of(mesh, in_plane) - q).norm(), 0.0, 1e-7) << i;
      double a = std::atan2(q.y(), q.x());
      if (a < 0) a += 2 * kPi;
      const int face = static_cast<int>(a / (2 * kPi / n));
      EXPECT_LE(std::min(std::abs(in_plane.face - face), n - std::abs(in_plane.face - face)), 2) << i;
    }
  }
  // The centre itself, shared by every face.
  EXPECT_NEAR(position_of(mesh, locator.closest(Vec3(0, 0, 1))).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace tvf
