#include "tvf/mesh/primitives.h"

#include "tvf/core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tvf {
namespace {

// Class I geodesic spheres: 10k² + 2 vertices, 20k² faces, closed with χ = 2, every
// vertex on the sphere, faces outward, and frequency 2^s is the s-times subdivided icosphere.
TEST(GeodesicSphere, CountsClosednessAndOrientation) {
  for (int k : {1, 2, 3, 7, 16}) {
    const Mesh m = make_geodesic_sphere(k, 2.0);
    EXPECT_EQ(m.num_vertices(), 10 * k * k + 2) << k;
    EXPECT_EQ(m.num_faces(), 20 * k * k) << k;
    EXPECT_TRUE(m.is_closed()) << k;
    EXPECT_EQ(m.euler_characteristic(), 2) << k;
    for (int v = 0; v < m.num_vertices(); ++v) EXPECT_NEAR(m.position(v).norm(), 2.0, 1e-12);
    for (int f = 0; f < m.num_faces(); ++f) {
      const Face& t = m.face(f);
      const Vec3 centre = (m.position(t[0]) + m.position(t[1]) + m.position(t[2])) / 3.0;
      EXPECT_GT(m.face_normal(f).dot(centre), 0) << "face " << f << " of k = " << k << " points inward";
    }
  }
  EXPECT_EQ(make_geodesic_sphere(45).num_vertices(), 20252);
  EXPECT_EQ(make_geodesic_sphere(8).num_vertices(), make_icosphere(3).num_vertices());
}

TEST(GeodesicSphere, RefusesFrequenciesOutOfRange) {
  EXPECT_THROW(make_geodesic_sphere(0), Error);
  EXPECT_THROW(make_geodesic_sphere(5000), Error);
}

}  // namespace
}  // namespace tvf
