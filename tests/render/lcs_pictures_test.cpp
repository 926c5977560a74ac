#include "tvf/render/lcs_pictures.h"

#include "support/test_fields.h"
#include "support/test_meshes.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace tvf {
namespace {

int red(std::uint32_t c) { return static_cast<int>((c >> 16) & 0xFF); }
int green(std::uint32_t c) { return static_cast<int>((c >> 8) & 0xFF); }

TEST(LcsPictures, MagmaRunsFromBlackToPaleYellow) {
  EXPECT_EQ(magma(0), 0x000004u);
  EXPECT_EQ(magma(1), 0xFCFDBFu);
  EXPECT_EQ(magma(-3), magma(0));
  EXPECT_EQ(magma(std::nan("")), magma(0));
  // Brighter along the map (sum of channels).
  auto sum = [](std::uint32_t c) { return ((c >> 16) & 0xFF) + ((c >> 8) & 0xFF) + (c & 0xFF); };
  for (int k = 1; k <= 10; ++k) EXPECT_GT(sum(magma(k / 10.0)), sum(magma((k - 1) / 10.0))) << k;
}

TEST(LcsPictures, ColourRangeIsThePercentilesOfTheFiniteValues) {
  std::vector<float> v;
  for (int k = 0; k <= 100; ++k) v.push_back(static_cast<float>(k));
  v.push_back(std::numeric_limits<float>::quiet_NaN());
  const auto [lo, hi] = colour_range(v);
  EXPECT_DOUBLE_EQ(lo, 1.0);
  EXPECT_DOUBLE_EQ(hi, 99.0);
}

TEST(LcsPictures, PlanarScalarIsInterpolatedAndNaNIsGray) {
  // Values x on [0, 2] × [0, 1]; the right half of the top row NaN.
  const Mesh grid = make_grid(GridSpec{21, 11, {0, 0}, {2, 1}});
  const TangentBundle bundle(grid);
  std::vector<float> values(static_cast<size_t>(grid.num_vertices()));
  for (int v = 0; v < grid.num_vertices(); ++v) values[static_cast<size_t>(v)] = static_cast<float>(grid.position(v).x());
  for (int ix = 15; ix < 21; ++ix) values[static_cast<size_t>(10 * 21 + ix)] = std::numeric_limits<float>::quiet_NaN();
  ScalarPictureOptions o;
  o.size = 200;
  o.lo = 0;
  o.hi = 2;
  o.legend = false;
  const Image img = scalar_picture(bundle, values, o);
  ASSERT_EQ(img.width, 200);
  ASSERT_EQ(img.height, 100);
  // Pixel i shows x = (i + ½)/100: magma((i + ½)/200), exactly up to rounding.
  for (const int i : {0, 50, 120, 199}) {
    const std::uint32_t expect = magma((i + 0.5) / 200.0);
    const std::uint32_t got = img.at(i, 60);
    EXPECT_NEAR(red(got), red(expect), 2) << i;
    EXPECT_NEAR(green(got), green(expect), 2) << i;
  }
  EXPECT_EQ(img.at(190, 1), o.nan_color);
  EXPECT_NE(img.at(20, 1), o.nan_color);
  o.legend = true;
  EXPECT_GT(scalar_picture(bundle, values, o).height, 100);
}

TEST(LcsPictures, CurvesAreDrawnOverTheTexture) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = test::field_from(bundle, TimeSampling{0, 1, 3}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  CurvePictureOptions o;
  o.size = 128;
  o.dots = false;
  o.line_width = 4;
  const std::vector<std::vector<Vec3>> curves{{Vec3(-0.8, 0, 0), Vec3(0.8, 0, 0)}};
  const Image img = curve_picture(bundle, field, 0.5, curves, std::vector<Vec3>{}, o);
  ASSERT_EQ(img.width, 128);
  // The middle row is the curve's colour; rows far from it are the gray texture.
  EXPECT_EQ(img.at(64, 64) & 0xFFFFFFu, o.color);
  const std::uint32_t far = img.at(64, 10);
  EXPECT_EQ(red(far), green(far));
}

TEST(LcsPictures, SurfacesAreDrawnByTheMeshRenderer) {
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  std::vector<float> values(static_cast<size_t>(sphere.num_vertices()));
  for (int v = 0; v < sphere.num_vertices(); ++v) values[static_cast<size_t>(v)] = static_cast<float>(sphere.position(v).z());
  ScalarPictureOptions o;
  o.size = 96;
  o.legend = false;
  const Image img = scalar_picture(bundle, values, o);
  ASSERT_EQ(img.width, 96);
  // The centre shows the sphere (not the white background), the corner the background.
  EXPECT_NE(img.at(48, 48), 0xFFFFFFu);
  EXPECT_EQ(img.at(0, 0), 0xFFFFFFu);
}

// A curve on the side of the sphere away from the default camera (direction 1, −0.6, 0.5):
// hidden from it, shown when the picture faces the curve (the mean normal at its points).
TEST(LcsPictures, OnSurfacesTheCameraFacesTheCurves) {
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field = test::field_from(bundle, TimeSampling{0, 1, 3}, [](const Vec3& x, double) {
    return Vec3(-x.y(), x.x(), 0);
  });
  std::vector<Vec3> arc;  // on the unit sphere about (−1, 0.6, −0.5)
  const Vec3 c = Vec3(-1, 0.6, -0.5).normalized(), t = c.cross(Vec3::UnitZ()).normalized();
  for (int k = -8; k <= 8; ++k) arc.push_back((c + 0.04 * k * t).normalized());
  CurvePictureOptions o;
  o.size = 128;
  o.line_width = 4;
  auto curve_pixels = [&](bool face) {
    o.face_curves = face;
    const Image img = curve_picture(bundle, field, 0.5, {arc}, std::vector<Vec3>{}, o);
    int n = 0;
    for (const std::uint32_t p : img.pixels) n += (p & 0xFFFFFFu) == o.color;
    return n;
  };
  EXPECT_EQ(curve_pixels(false), 0) << "behind the sphere from the default camera";
  EXPECT_GT(curve_pixels(true), 50);
}

// A streakline's particles close together (as `tvf streaklines` draws them: dots at the
// default width) are the curve's colour on a surface as on the plane, with a thin casing:
// each dot had a black outline, and they merged into a black band (4–10 red pixels against
// ~400 black on a sphere).
TEST(LcsPictures, OnSurfacesDenseDotsKeepTheCurvesColour) {
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field = test::field_from(bundle, TimeSampling{0, 1, 3}, [](const Vec3& x, double) {
    return Vec3(-x.y(), x.x(), 0);
  });
  std::vector<Vec3> arc;  // 0.004 apart, facing the camera
  const Vec3 c = Vec3(1, -0.6, 0.5).normalized(), t = c.cross(Vec3::UnitZ()).normalized();
  for (int k = -50; k <= 50; ++k) arc.push_back((c + 0.004 * k * t).normalized());
  CurvePictureOptions o;
  o.size = 400;
  o.face_curves = false;
  const Image img = curve_picture(bundle, field, 0.5, {arc}, std::vector<Vec3>{}, o);
  int coloured = 0, black = 0;
  for (const std::uint32_t p : img.pixels) {
    coloured += (p & 0xFFFFFFu) == o.color;
    black += (p & 0xFFFFFFu) == 0;
  }
  EXPECT_GT(coloured, 100);
  EXPECT_GT(coloured, black) << coloured << " pixels of the curve's colour, " << black << " black";
}

}  // namespace
}  // namespace tvf
