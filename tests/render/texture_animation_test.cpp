// Texture animation (IBFV): coherent from frame to frame, moving with the flow, the
// singularity overlay in the paper's colours, and frames written all or nothing.
#include "tvf/render/texture_animation.h"

#include "support/test_fields.h"
#include "support/test_paths.h"
#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"
#include "tvf/integrate/streamline.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"
#include "tvf/render/plots.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

// A field sampled from f(x, y, t) on every frame.
template <class F>
Field sample(const Mesh& mesh, TimeSampling ts, F&& f) {
  Field field(ts, mesh.num_vertices());
  for (int j = 0; j < ts.frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v)
      field.at(j, v) = f(cplx(mesh.position(v).x(), mesh.position(v).y()), ts.time(j));
  return field;
}

double mean_abs_difference(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += std::abs(a[k] - b[k]);
  return s / static_cast<double>(a.size());
}

// Pearson correlation of a and b over the pixels with margin ≤ x < w − margin.
double correlation(const std::vector<float>& a, const std::vector<float>& b, int w, int h, int margin) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, n = 0;
  for (int y = margin; y < h - margin; ++y)
    for (int x = margin; x < w - margin; ++x) {
      const double p = a[static_cast<size_t>(y * w + x)], q = b[static_cast<size_t>(y * w + x)];
      sa += p, sb += q, saa += p * p, sbb += q * q, sab += p * q, n += 1;
    }
  const double cov = sab / n - sa / n * sb / n;
  return cov / std::sqrt((saa / n - sa / n * sa / n) * (sbb / n - sb / n * sb / n));
}

TEST(TextureAnimation, PixelsCoverTheDomainBoxOnItsLongSide) {
  const Mesh grid = make_grid(GridSpec{9, 5, {-2, 0}, {2, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 3}, [](cplx, double) { return cplx(1, 0); });
  TextureOptions o;
  o.size = 200;
  const TextureAnimator a(bundle, field, o);
  EXPECT_EQ(a.width(), 200);
  EXPECT_EQ(a.height(), 50);
  EXPECT_DOUBLE_EQ(a.pixels_per_unit(), 50.0);
  EXPECT_TRUE(a.to_pixel(Vec2(-2, 1)).isApprox(Vec2(0, 0)));
  EXPECT_TRUE(a.to_pixel(Vec2(2, 0)).isApprox(Vec2(200, 50)));
}

// Gray levels of a picture in [0, 1].
std::vector<float> gray_levels(const Image& img) {
  std::vector<float> g(img.pixels.size());
  for (size_t k = 0; k < g.size(); ++k) g[k] = static_cast<float>(img.pixels[k] & 255u) / 255.0f;
  return g;
}

TEST(TextureAnimation, FramesOfASlowlyVaryingFieldAreCoherent) {
  const Mesh grid = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // A center drifting slowly to the right.
  const Field field = sample(grid, TimeSampling{0, 1, 40}, [](cplx x, double t) {
    return cplx(0, 1) * (x - cplx(-0.2 + 0.4 * t, 0));
  });
  // The same center held still at its first position.
  const Field steady = sample(grid, TimeSampling{0, 1, 40}, [](cplx x, double) { return cplx(0, 1) * (x - cplx(-0.2, 0)); });
  TextureOptions o;
  o.size = 256;
  TextureAnimator a(bundle, field, o);
  TextureAnimator still(bundle, steady, o);
  o.seed = 99;
  TextureAnimator other(bundle, field, o);
  double consecutive = 0, consecutive_still = 0, unrelated = 0;
  std::vector<float> prev, prev_still;
  for (int k = 0; k < 20; ++k) {
    const double t = field.time().time(k);
    a.advance(t);
    still.advance(t);
    other.advance(t);
    const std::vector<float> now = gray_levels(a.picture()), now_still = gray_levels(still.picture());
    if (k > 0) {
      consecutive = std::max(consecutive, mean_abs_difference(prev, now));
      consecutive_still = std::max(consecutive_still, mean_abs_difference(prev_still, now_still));
    }
    unrelated += mean_abs_difference(gray_levels(other.picture()), now) / 20;
    prev = now;
    prev_still = now_still;
  }
  // The pictures change from one frame to the next by a small fraction of how much two
  // unrelated textures of the same field differ (the change is the texture streaming
  // along the flow)...
  EXPECT_LT(consecutive, 0.4 * unrelated) << consecutive << " vs " << unrelated;
  EXPECT_GT(unrelated, 0.1);
  // ... and the field's slow change adds little to it: about as much as a steady field's.
  EXPECT_LT(consecutive, 1.15 * consecutive_still) << consecutive << " vs " << consecutive_still;
}

TEST(TextureAnimation, TextureMovesWithAUniformTranslation) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 11}, [](cplx, double) { return cplx(0.7, 0); });
  TextureOptions o;
  o.size = 128;
  o.pixels_per_frame = 3;  // exactly three pixels to the right per frame
  TextureAnimator a(bundle, field, o);
  a.advance(0.0);
  for (int k = 1; k < 6; ++k) {
    const std::vector<float> before = a.texture();
    a.advance(field.time().time(k));
    const std::vector<float>& after = a.texture();
    const int w = a.width(), h = a.height();
    std::vector<float> moved(before.size());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) moved[static_cast<size_t>(y * w + x)] = before[static_cast<size_t>(y * w + std::max(0, x - 3))];
    const double with_flow = correlation(after, moved, w, h, 8);
    const double in_place = correlation(after, before, w, h, 8);
    EXPECT_GT(with_flow, in_place + 0.02) << k;
    EXPECT_GT(with_flow, 0.9) << k;  // (1 − α) of the texture is the moved one
  }
}

TEST(TextureAnimation, OverlayMarksSingularitiesInThePapersColours) {
  const Mesh grid = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // A source at (−0.5, 0.3) and a sink at (0.4, −0.4), joined by a saddle between them.
  const Field field = sample(grid, TimeSampling{0, 1, 2}, [](cplx x, double) {
    return (x - cplx(-0.5, 0.3)) * (x - cplx(0.4, -0.4));
  });
  TextureOptions o;
  o.size = 200;
  TextureAnimator a(bundle, field, o);
  a.advance(0);
  Image img = a.picture();
  draw_singularities(img, a, bundle, field, 0);
  const auto sing = find_singularities(bundle, values_at(field, 0));
  ASSERT_FALSE(sing.empty());
  for (const Singularity& s : sing) {
    const Vec2 p = a.to_pixel(s.position.head<2>());
    const std::uint32_t c = img.at(static_cast<int>(p.x()), static_cast<int>(p.y()));
    const auto want = type_color(s.type);
    EXPECT_NEAR(((c >> 16) & 255) / 255.0, want[0], 0.01) << to_string(s.type);
    EXPECT_NEAR(((c >> 8) & 255) / 255.0, want[1], 0.01) << to_string(s.type);
    EXPECT_NEAR((c & 255) / 255.0, want[2], 0.01) << to_string(s.type);
  }
}

TEST(TextureAnimation, PathsOverlayTrailsASingularityUpToTheFrame) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // A source moving from (−0.5, 0.01) to (0.5, 0.01): its path is a horizontal segment.
  const Field field = sample(grid, TimeSampling{0, 1, 11}, [](cplx x, double t) { return x - cplx(-0.5 + t, 0.01); });
  TextureOptions o;
  o.size = 600;
  TextureAnimator a(bundle, field, o);
  a.advance(0.5);
  const Topology topology = analyze_topology(bundle, field);
  Image img = a.picture();
  draw_singularity_paths(img, a, topology, 0.5);
  const auto green = type_color(SingularityType::source);
  auto is_green = [&](Vec2 x) {
    const Vec2 p = a.to_pixel(x);
    const std::uint32_t c = img.at(static_cast<int>(p.x()), static_cast<int>(p.y()));
    return std::abs(((c >> 16) & 255) / 255.0 - green[0]) < 0.02 && std::abs(((c >> 8) & 255) / 255.0 - green[1]) < 0.02 &&
           std::abs((c & 255) / 255.0 - green[2]) < 0.02;
  };
  EXPECT_TRUE(is_green(Vec2(-0.4, 0.01)));   // where it has been
  EXPECT_TRUE(is_green(Vec2(-0.1, 0.01)));
  EXPECT_FALSE(is_green(Vec2(0.2, 0.01)));   // where it has not been yet
  EXPECT_FALSE(is_green(Vec2(-0.4, 0.2)));   // off the path
}

TEST(TextureAnimation, StreamlinesOverlayFollowsTheField) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 2}, [](cplx, double) { return cplx(1, 0); });
  TextureOptions o;
  o.size = 200;
  o.contrast = 1e-6;  // a flat gray picture, so only the lines are dark
  TextureAnimator a(bundle, field, o);
  a.advance(0);
  Image img = a.picture();
  draw_streamlines(img, a, bundle, field, 0, 20.0);
  // Horizontal lines 20 pixels apart: dark rows, each dark all the way across, between
  // rows of plain gray.
  int dark_rows = 0;
  for (int y = 0; y < img.height; ++y) {
    int dark = 0;
    for (int x = 0; x < img.width; ++x) dark += (img.at(x, y) & 255u) < 100u;  // the gray is 128
    if (dark > 0) {
      EXPECT_GT(dark, img.width * 9 / 10) << y;
      ++dark_rows;
    }
  }
  EXPECT_GE(dark_rows, 9);
  EXPECT_LE(dark_rows, 2 * 11);
}

TEST(TextureAnimation, SendsSurfacesElsewhereAndRefusesBadOptions) {
  const Mesh sphere = make_icosphere(1);
  const TangentBundle bs(sphere);
  const Field fs(TimeSampling{0, 1, 2}, sphere.num_vertices());
  const std::string msg = test::error_of([&] { TextureAnimator(bs, fs); });
  EXPECT_NE(msg.find("SurfaceTextureAnimator"), std::string::npos) << msg;

  const Mesh grid = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field(TimeSampling{0, 1, 2}, grid.num_vertices());
  TextureOptions o;
  o.size = 4;
  EXPECT_NE(test::error_of([&] { TextureAnimator(bundle, field, o); }).find("size"), std::string::npos);
  o = {};
  o.alpha = 0;
  EXPECT_NE(test::error_of([&] { TextureAnimator(bundle, field, o); }).find("alpha"), std::string::npos);
  o = {};
  o.contrast = std::nan("");
  EXPECT_NE(test::error_of([&] { TextureAnimator(bundle, field, o); }).find("contrast"), std::string::npos);
}

TEST(TextureAnimation, HandsPicturesOnWithoutFilesAndAsTheFilesHoldThem) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 6}, [](cplx x, double) { return cplx(0, 1) * x; });
  TextureAnimationOptions o;
  o.texture.size = 40;
  o.first = 2;
  o.last = 4;
  std::vector<int> order;
  std::vector<Image> pictures;
  o.on_picture = [&](int k, const Image& img) {
    order.push_back(k);
    pictures.push_back(img);
  };
  // Without frames_dir or video: pictures only.
  const auto r = write_texture_animation(bundle, field, o);
  EXPECT_EQ(r.frames, 3);
  EXPECT_TRUE(r.files.empty());
  ASSERT_EQ(order, (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(pictures[0].width, 40);
  EXPECT_EQ(pictures[0].height, 40);
  // The PNG frames of the same run hold the same pixels.
  test::TempDir dir;
  o.frames_dir = (dir / "frames").string();
  const std::vector<Image> without_files = pictures;
  order.clear();
  pictures.clear();
  write_texture_animation(bundle, field, o);
  ASSERT_EQ(order, (std::vector<int>{2, 3, 4}));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(pictures[static_cast<size_t>(i)].pixels, without_files[static_cast<size_t>(i)].pixels);
    const Image png = read_png((dir / "frames" / fmt::format("frame_{:05d}.png", i + 2)).string());
    ASSERT_EQ(png.pixels.size(), pictures[static_cast<size_t>(i)].pixels.size());
    size_t differ = 0;  // RGB compared (the unused top byte aside)
    for (size_t q = 0; q < png.pixels.size(); ++q)
      differ += (png.pixels[q] & 0xFFFFFFu) != (pictures[static_cast<size_t>(i)].pixels[q] & 0xFFFFFFu);
    EXPECT_EQ(differ, 0u);
  }
  // Neither files nor pictures asked for: refused as before.
  o.frames_dir.clear();
  o.on_picture = {};
  EXPECT_NE(test::error_of([&] { write_texture_animation(bundle, field, o); }).find("give a folder"),
            std::string::npos);
}

TEST(TextureAnimation, WritesEveryFrameOrNothing) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 6}, [](cplx x, double) { return cplx(0, 1) * x; });
  test::TempDir dir;
  TextureAnimationOptions o;
  o.texture.size = 48;
  o.frames_dir = (dir / "frames").string();
  o.first = 1;
  o.last = 4;
  int calls = 0;
  o.progress = [&](int done, int total) {
    EXPECT_EQ(total, 4);
    EXPECT_EQ(done, ++calls);
  };
  const auto r = write_texture_animation(bundle, field, o);
  EXPECT_EQ(r.frames, 4);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir.path())) names.push_back(e.path().filename().string());
  ASSERT_EQ(names, std::vector<std::string>{"frames"});  // no temporary left
  for (int k = 1; k <= 4; ++k) {
    const Image img = read_png((dir / "frames" / fmt::format("frame_{:05d}.png", k)).string());
    EXPECT_EQ(img.width, 48);
    EXPECT_EQ(img.height, 48);
  }
  EXPECT_FALSE(fs::exists(dir / "frames" / "frame_00000.png"));
  // A second run replaces the folder as a whole.
  o.progress = {};
  o.first = 0;
  o.last = 1;
  write_texture_animation(bundle, field, o);
  EXPECT_TRUE(fs::exists(dir / "frames" / "frame_00000.png"));
  EXPECT_FALSE(fs::exists(dir / "frames" / "frame_00004.png"));
  // Bad options leave the previous output untouched and nothing new.
  o.last = 9;
  EXPECT_NE(test::error_of([&] { write_texture_animation(bundle, field, o); }).find("last frame"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "frames" / "frame_00001.png"));
  names.clear();
  for (const auto& e : fs::directory_iterator(dir.path())) names.push_back(e.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{"frames"});
  // A folder holding anything but frames is never replaced.
  o.last = 1;
  test::write_text(dir / "frames" / "notes.txt", "mine");
  EXPECT_NE(test::error_of([&] { write_texture_animation(bundle, field, o); }).find("notes.txt"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "frames" / "notes.txt"));
  o.frames_dir = dir.path().string() + "/new/";  // a trailing slash names the folder itself
  write_texture_animation(bundle, field, o);
  EXPECT_TRUE(fs::exists(dir / "new" / "frame_00001.png"));
}

TEST(TextureAnimation, DyeIsCarriedByTheFieldTimesItsTimeScale) {
  // A uniform flow (0.2, 0) over t ∈ [0, 1]: with dye_time_scale 3 the dye released at t = 0
  // is 0.6 downstream of its seed at t = 1; a scale of 1 carries it with the field itself.
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = test::field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3&, double) { return Vec3(0.2, 0, 0); });
  TextureAnimationOptions o;
  o.streakline_seeds = {Vec3(-0.5, 0.1, 0)};
  o.dye_time_scale = 3;
  const std::optional<Field> scaled = texture_dye_field(field, o);
  ASSERT_TRUE(scaled.has_value());
  std::optional<DyeInjector> dye = texture_dye(bundle, *scaled, o, 5);
  ASSERT_TRUE(dye.has_value());
  EXPECT_DOUBLE_EQ(dye->release_spacing(), 0.0625);  // a quarter of the pictures' spacing
  dye->advance(1.0);
  const Streakline line = dye->streakline(0);
  ASSERT_EQ(line.points.size(), 17u);
  EXPECT_NEAR((line.points.front().position - Vec3(0.1, 0.1, 0)).norm(), 0.0, 1e-9);
  o.dye_time_scale = 1;
  EXPECT_FALSE(texture_dye_field(field, o).has_value());
  o.dye_time_scale = 0;
  EXPECT_NE(test::error_of([&] { texture_dye_field(field, o); }).find("dye time scale"), std::string::npos);
  o.streakline_seeds.clear();
  o.dye_time_scale = 1;
  EXPECT_FALSE(texture_dye(bundle, field, o, 5).has_value());
}

}  // namespace
}  // namespace tvf
