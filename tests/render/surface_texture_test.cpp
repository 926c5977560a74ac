// Surfaces seen from a camera: the offscreen renderer draws a sphere as its projected
// disc, hides lines behind it, and the texture animation on a surface is coherent from
// frame to frame, moves with the flow and makes a video of the right length.
#include "tvf/render/mesh_renderer.h"
#include "tvf/render/surface_texture.h"

#include "support/test_meshes.h"
#include "support/test_paths.h"
#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"
#include "tvf/integrate/streamline.h"
#include "tvf/mesh/primitives.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/video.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

// A field sampled from a world vector field w(x, t), projected into each vertex basis.
template <class W>
Field sample_world(const TangentBundle& bundle, TimeSampling ts, W&& w) {
  const Mesh& mesh = bundle.mesh();
  Field field(ts, mesh.num_vertices());
  for (int j = 0; j < ts.frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) field.at(j, v) = bundle.world_to_vertex(v, w(mesh.position(v), ts.time(j)));
  return field;
}

double correlation(const std::vector<float>& a, const std::vector<float>& b) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const double n = static_cast<double>(a.size());
  for (size_t k = 0; k < a.size(); ++k) {
    sa += a[k], sb += b[k], saa += a[k] * a[k], sbb += b[k] * b[k], sab += a[k] * b[k];
  }
  const double cov = sab / n - sa / n * sb / n;
  return cov / std::sqrt((saa / n - sa / n * sa / n) * (sbb / n - sb / n * sb / n));
}

TEST(MeshRenderer, SphereFillsItsProjectedDisc) {
  const Mesh sphere = make_icosphere(4, 1.0);
  MeshRenderer renderer;
  renderer.set_mesh(sphere);
  renderer.set_colors(std::vector<std::uint32_t>(static_cast<size_t>(sphere.num_vertices()), 0xFFFFFFu));
  RenderOptions o;
  o.width = 240;
  o.height = 200;
  o.background = 0x000000;
  o.lighting = false;
  o.samples = 0;
  const Camera cam = Camera::framing(sphere.bbox_min(), sphere.bbox_max(), Vec3(0.3, -1, 0.4), Vec3(0, 0, 1),
                                     static_cast<double>(o.width) / o.height, 30.0, 1.6);
  const Image img = renderer.render(cam, o);
  ASSERT_EQ(img.width, 240);
  ASSERT_EQ(img.height, 200);
  // The silhouette of a sphere of radius 1 seen from distance D is a circle of angular
  // radius asin(1/D) around the centre's projection.
  const double dist = (cam.eye - cam.target).norm();
  const double r = 0.5 * o.height * std::tan(std::asin(1.0 / dist)) / std::tan(15.0 * kPi / 180.0);
  const Vec3 c = cam.project(Vec3::Zero(), o.width, o.height);
  EXPECT_NEAR(c.x(), 120.0, 1e-9);
  EXPECT_NEAR(c.y(), 100.0, 1e-9);
  int lit = 0, wrong = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double d = std::hypot(x + 0.5 - c.x(), y + 0.5 - c.y());
      const bool on = img.at(x, y) == 0xFFFFFFu;
      lit += on;
      if ((d < r - 1.0 && !on) || (d > r + 1.0 && img.at(x, y) != 0u)) ++wrong;
    }
  EXPECT_EQ(wrong, 0);
  EXPECT_NEAR(lit, kPi * r * r, 0.02 * kPi * r * r) << "r = " << r;
}

TEST(Camera, FramingPointsTouchesTheMarginExactly) {
  const Mesh torus = make_torus(24, 12);
  for (const Vec3& dir : {Vec3(1, -0.6, 0.5), Vec3(0, 0, 1), Vec3(-1, 2, 0.1)}) {
    const double aspect = 1.5, margin = 1.1;
    const Camera c = Camera::framing(torus.positions(), dir, Vec3(0, 0, 1), aspect, 40.0, margin);
    EXPECT_NEAR((c.eye - c.target).normalized().dot(dir.normalized()), 1.0, 1e-12);
    double widest = 0;
    for (const Vec3& p : torus.positions()) {
      const Vec3 q = c.project(p, 300, 200);
      widest = std::max({widest, std::abs(q.x() - 150) / 150, std::abs(q.y() - 100) / 100});
    }
    // The farthest-out point sits at 1/margin of the half-width or half-height.
    EXPECT_NEAR(widest, 1 / margin, 1e-9) << dir.transpose();
  }
}

TEST(MeshRenderer, LinesAndMarkersShowInFrontAndHideBehind) {
  const Mesh sphere = make_icosphere(3, 1.0);
  MeshRenderer renderer;
  renderer.set_mesh(sphere);
  renderer.set_colors(std::vector<std::uint32_t>(static_cast<size_t>(sphere.num_vertices()), 0x808080u));
  RenderOptions o;
  o.width = o.height = 160;
  o.lighting = false;
  o.samples = 0;
  const Camera cam = Camera::framing(sphere.bbox_min(), sphere.bbox_max(), Vec3(0, 0, 1), Vec3(0, 1, 0));
  // A red line across the front pole, a green one across the back, a blue marker in front.
  // (Densely sampled on the sphere, so that the chords stay above the mesh's faces.)
  RenderLine front{{}, 0xFF0000, 4};
  for (int k = 0; k <= 60; ++k) {
    const double a = (k / 60.0 - 0.5) * kPi / 3;
    front.points.push_back(Vec3(std::sin(a), 0, std::cos(a)));
  }
  RenderLine back{{Vec3(-0.5, 0.3, -0.8), Vec3(0.5, 0.3, -0.8)}, 0x00FF00, 4};
  const RenderMarker marker{Vec3(0, -0.5, std::sqrt(0.75)), 0x0000FF, 6};
  const Image img = renderer.render(cam, o, std::vector<RenderLine>{front, back}, std::vector<RenderMarker>{marker});
  int red = 0, green = 0, blue = 0;
  for (const auto p : img.pixels) {
    red += p == 0xFF0000u;
    green += p == 0x00FF00u;
    blue += p == 0x0000FFu;
  }
  EXPECT_GT(red, 40);
  EXPECT_EQ(green, 0);
  EXPECT_GT(blue, 40);
  const Vec3 m = cam.project(marker.position, o.width, o.height);
  EXPECT_EQ(img.at(static_cast<int>(m.x()), static_cast<int>(m.y())), 0x0000FFu);
  // A casing lies under its line: the line keeps every pixel, the casing shows around it.
  RenderLine cased = front;
  cased.casing = true;
  const Image with_casing = renderer.render(cam, o, std::vector<RenderLine>{cased});
  const Image without = renderer.render(cam, o, std::vector<RenderLine>{front});
  int red_cased = 0, red_plain = 0, black = 0;
  for (size_t k = 0; k < without.pixels.size(); ++k) {
    red_cased += with_casing.pixels[k] == 0xFF0000u;
    red_plain += without.pixels[k] == 0xFF0000u;
    black += with_casing.pixels[k] == 0u;
  }
  EXPECT_EQ(red_cased, red_plain);
  EXPECT_GT(black, red_plain / 2);
  // An underlay three times as wide under the same points: the line keeps every pixel
  // (drawn as an ordinary line first, it hid every one of them), the underlay shows round it.
  RenderLine under = front;
  under.color = 0x0000FF;
  under.width = 12;
  under.casing = true;
  under.underlay = true;
  const Image over = renderer.render(cam, o, std::vector<RenderLine>{under, front});
  int red_over = 0, blue_over = 0;
  for (const auto p : over.pixels) {
    red_over += p == 0xFF0000u;
    blue_over += p == 0x0000FFu;
  }
  EXPECT_EQ(red_over, red_plain);
  EXPECT_GT(blue_over, red_plain);
}

TEST(MeshRenderer, RefusesBadInput) {
  MeshRenderer renderer;
  const std::vector<Vec3> pts{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_NE(test::error_of([&] { renderer.set_mesh(pts, std::vector<Face>{{0, 1, 3}}); }).find("vertex 3"),
            std::string::npos);
  renderer.set_mesh(pts, std::vector<Face>{{0, 1, 2}});
  EXPECT_NE(test::error_of([&] { renderer.set_colors(std::vector<std::uint32_t>(2, 0u)); }).find("2 colours"),
            std::string::npos);
  RenderOptions o;
  o.width = 0;
  EXPECT_NE(test::error_of([&] { renderer.render(Camera{}, o); }).find("0×800"), std::string::npos);
  EXPECT_NE(test::error_of([] { Camera::framing(Vec3::Zero(), Vec3::Ones(), Vec3::Zero(), Vec3::UnitZ()); })
                .find("direction"),
            std::string::npos);
}

// A slowly varying rotation about the z axis, and a test texture on a sphere.
struct Spin {
  Mesh sphere = make_icosphere(3, 1.0);
  TangentBundle bundle{sphere};
  Field field = sample_world(bundle, TimeSampling{0, 1, 41}, [](const Vec3& x, double t) {
    return Vec3(Vec3::UnitZ().cross(x) * (1.0 + 0.2 * t));
  });
};

TEST(SurfaceTexture, SamplesCoverTheSurfaceAtTheWantedSpacing) {
  Spin s;
  TextureOptions o;
  o.size = 200;
  SurfaceView v;
  v.spacing = 2;
  const SurfaceTextureAnimator a(s.bundle, s.field, o, v);
  EXPECT_GT(a.subdivision(), 1);
  // Every sample lies on the mesh; the small triangles tile it (same total area).
  double area = 0;
  for (const Face& t : a.sample_triangles()) {
    const auto& p = a.sample_positions();
    area += 0.5 * (p[static_cast<size_t>(t[1])] - p[static_cast<size_t>(t[0])])
                      .cross(p[static_cast<size_t>(t[2])] - p[static_cast<size_t>(t[0])])
                      .norm();
  }
  double mesh_area = 0;
  for (int f = 0; f < s.sphere.num_faces(); ++f) mesh_area += s.sphere.face_area(f);
  EXPECT_NEAR(area, mesh_area, 1e-9 * mesh_area);
  const size_t n = static_cast<size_t>(a.subdivision());
  EXPECT_EQ(a.sample_triangles().size(), static_cast<size_t>(s.sphere.num_faces()) * n * n);
  // Closed mesh: V − E + F = 2 for the subdivided mesh too.
  const long nv = static_cast<long>(a.sample_positions().size());
  const long nf = static_cast<long>(a.sample_triangles().size());
  EXPECT_EQ(nv - 3 * nf / 2 + nf, 2);
  // Small edges are about `spacing` pixels: the mean edge over ppu.
  EXPECT_LE(s.sphere.mean_edge_length() / a.subdivision() * a.pixels_per_unit(), 2.0);
  EXPECT_GT(s.sphere.mean_edge_length() / (a.subdivision() - 1) * a.pixels_per_unit(), 2.0);
}

TEST(SurfaceTexture, FramesAreCoherentAndMoveWithTheFlow) {
  Spin s;
  TextureOptions o;
  o.size = 160;
  o.lic = 0;
  o.alpha = 0.1;
  o.pixels_per_frame = 3;
  o.warmup = 15;
  const double dt = 1.0 / 40;
  SurfaceTextureAnimator a(s.bundle, s.field, o);
  a.advance(0.5);
  const std::vector<float> f0 = a.texture();
  a.advance(0.5 + dt);
  const std::vector<float> f1 = a.texture();
  // Another seed: an unrelated texture of the same statistics.
  TextureOptions o2 = o;
  o2.seed = 7;
  SurfaceTextureAnimator b(s.bundle, s.field, o2);
  b.advance(0.5);
  const double coherent = correlation(f0, f1), unrelated = correlation(f0, b.texture());
  EXPECT_GT(coherent, 0.75) << coherent << " unrelated " << unrelated;
  EXPECT_LT(std::abs(unrelated), 0.05);
  // The texture moves with the flow: frame 1 at a sample matches frame 0 where the
  // rotation about z carried it from (by the step's angle at the sample's radius) better
  // than frame 0 at the same place. (c repeats a's first frame: f0 at any point.)
  SurfaceTextureAnimator c(s.bundle, s.field, o);
  c.advance(0.5);
  ASSERT_EQ(c.texture(), f0);
  std::vector<float> after, moved, in_place;
  const double step_px = o.pixels_per_frame;  // uniform speed: pixels per frame of the field
  for (size_t k = 0; k < f1.size(); k += 3) {
    const Vec3& x = a.sample_positions()[k];
    const double rho = std::hypot(x.x(), x.y());
    if (rho < 0.4) continue;
    const double angle = -step_px / a.pixels_per_unit() / rho;
    const Vec3 from(std::cos(angle) * x.x() - std::sin(angle) * x.y(), std::sin(angle) * x.x() + std::cos(angle) * x.y(),
                    x.z());
    after.push_back(f1[k]);
    moved.push_back(c.texture_at(closest_point(s.sphere, from)));
    in_place.push_back(f0[k]);
  }
  ASSERT_GT(after.size(), 1000u);
  const double with_flow = correlation(after, moved), still = correlation(after, in_place);
  EXPECT_GT(with_flow, still + 0.03) << with_flow << " vs " << still;
  EXPECT_GT(with_flow, 0.8);  // (1 − α) of the texture is the moved one
}

TEST(SurfaceTexture, StreamlineOverlayFollowsTheFieldOnTheSurface) {
  Spin s;
  // The rotation about z: streamlines are circles of constant height on the sphere.
  const auto lines = surface_streamline_lines(s.bundle, s.field, 0.5, 30, 1.5, 3);
  ASSERT_GE(lines.size(), 25u);  // seeds on the poles' faces may stop at once
  for (const RenderLine& l : lines) {
    ASSERT_GE(l.points.size(), 2u);
    double zmin = l.points[0].z(), zmax = zmin;
    for (const Vec3& p : l.points) {
      EXPECT_NEAR(p.norm(), 1.0, 0.02);  // on the mesh (its faces are chords of the sphere)
      zmin = std::min(zmin, p.z());
      zmax = std::max(zmax, p.z());
    }
    EXPECT_LT(zmax - zmin, 0.03);
  }
}

TEST(SurfaceTexture, OpenSurfacesKeepAFiniteTexture) {
  // A hemisphere (boundary on the equator) with flow leaving and entering through it.
  const Mesh& mesh = test::hemisphere_mesh();
  const TangentBundle bundle(mesh);
  const Field field = sample_world(bundle, TimeSampling{0, 1, 5}, [](const Vec3& x, double t) {
    return Vec3(Vec3(1, 0.5 * t, 0) - x.dot(Vec3(1, 0.5 * t, 0)) * x);
  });
  TextureOptions o;
  o.size = 96;
  SurfaceTextureAnimator a(bundle, field, o);
  for (int k = 0; k < 5; ++k) a.advance(field.time().time(k));
  for (const float v : a.texture()) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << v;
  const auto shown = a.shown();
  const auto [lo, hi] = std::minmax_element(shown.begin(), shown.end());
  EXPECT_EQ(*lo, 0.0f);  // contrast stretched over the whole range
  EXPECT_EQ(*hi, 1.0f);
}

TEST(SurfaceTexture, VideoOfASurfaceHasEveryFrame) {
  if (!ffmpeg_available() || test::run_command("command -v ffprobe >/dev/null 2>&1").exit_code != 0)
    GTEST_SKIP() << "ffmpeg/ffprobe not installed (Debian package ffmpeg)";
  Spin s;
  test::TempDir dir;
  TextureAnimationOptions o;
  o.texture.size = 96;
  o.frames = 7;
  o.video = (dir / "spin.mp4").string();
  o.frames_dir = (dir / "frames").string();
  o.overlay_singularities = true;
  const TextureAnimationReport r = write_texture_animation(s.bundle, s.field, o);
  EXPECT_EQ(r.frames, 7);
  EXPECT_EQ(r.width, 96);
  const auto p = test::run_command("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                   "stream=nb_read_frames -of csv=p=0 '" + o.video + "'");
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_EQ(std::stoi(p.output), 7);
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(dir / "frames")) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 7);
  // A frame shows the textured sphere: many gray levels inside, white around, and the
  // rotation's center near the north pole (in view from the default direction) as a
  // magenta marker (0.8, 0.1, 0.8) where the camera sees it.
  const Image img = read_png((dir / "frames" / "frame_00003.png").string());
  int white = 0;
  std::vector<int> levels(256, 0);
  for (const auto px : img.pixels) {
    white += px == 0xFFFFFFu;
    const auto r8 = (px >> 16) & 255u, g8 = (px >> 8) & 255u, b8 = px & 255u;
    if (r8 == g8 && g8 == b8) ++levels[r8];
  }
  SurfaceTextureAnimator a(s.bundle, s.field, o.texture, o.surface);
  const auto sing = find_singularities(s.bundle, values_at(s.field, 0.5));  // frame 3 of 7
  ASSERT_EQ(sing.size(), 2u);
  const Vec3 north = sing[0].position.z() > 0 ? sing[0].position : sing[1].position;
  EXPECT_GT(north.z(), 0.95);
  const Vec3 pole = a.camera().project(north, img.width, img.height);
  const std::uint32_t at_pole = img.at(static_cast<int>(pole.x()), static_cast<int>(pole.y()));
  EXPECT_EQ(at_pole, rgb(204, 26, 204)) << std::hex << at_pole;
  EXPECT_GT(white, img.width * img.height / 5);
  EXPECT_GT(std::count_if(levels.begin(), levels.end(), [](int n) { return n > 0; }), 100);
}


// --- Image-space advection (SurfaceImageAnimator) ----------------------------------------

TEST(SurfaceImage, TexelsSeeTheNearestPointOfTheSurface) {
  Spin s;
  TextureOptions o;
  o.size = 120;
  const SurfaceImageAnimator a(s.bundle, s.field, o);
  ASSERT_EQ(a.grid(), 120);
  const Camera& cam = a.camera();
  const double dist = (cam.eye - cam.target).norm();
  const Vec3 c = cam.project(Vec3::Zero(), 120, 120);
  // The silhouette of the (faceted) unit sphere: a circle of angular radius asin(1/D).
  const double r = 60.0 * std::tan(std::asin(1.0 / dist)) / std::tan(15.0 * kPi / 180.0);
  int seen = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 120; ++x) {
      const size_t k = static_cast<size_t>(y) * 120 + static_cast<size_t>(x);
      const double d = std::hypot(x + 0.5 - c.x(), y + 0.5 - c.y());
      const int f = a.texel_faces()[k];
      if (d > r + 0.5) {
        EXPECT_EQ(f, -1) << x << "," << y;
      }
      if (d < r - 2.0) {
        EXPECT_GE(f, 0) << x << "," << y;  // inside the inscribed polygon
      }
      if (f < 0) continue;
      ++seen;
      // The point seen projects onto the texel's centre, lies on the face, and faces the eye
      // (the nearest of the two points where the ray meets the sphere).
      const Vec3 p = a.texel_position(k);
      const Vec3 q = cam.project(p, 120, 120);
      EXPECT_NEAR(q.x(), x + 0.5, 1e-3);
      EXPECT_NEAR(q.y(), y + 0.5, 1e-3);
      EXPECT_NEAR(p.norm(), 1.0, 0.02);
      EXPECT_GT(s.bundle.face_normal(f).dot(cam.eye - p), 0.0);
    }
  EXPECT_NEAR(seen, kPi * r * r, 0.03 * kPi * r * r);
}

TEST(SurfaceImage, FramesAreCoherentAndMoveWithTheFlow) {
  Spin s;
  TextureOptions o;
  o.size = 160;
  o.lic = 0;
  o.pixels_per_frame = 6;
  o.warmup = 15;
  const double dt = 1.0 / 40;
  SurfaceImageAnimator a(s.bundle, s.field, o);
  a.advance(0.5);
  const std::vector<float> f0 = a.texture();
  a.advance(0.5 + dt);
  const std::vector<float> f1 = a.texture();
  TextureOptions o2 = o;
  o2.seed = 7;
  SurfaceImageAnimator b(s.bundle, s.field, o2);
  b.advance(0.5);
  std::vector<float> s0, s1, sb;
  for (size_t k = 0; k < f0.size(); ++k)
    if (a.texel_faces()[k] >= 0) s0.push_back(f0[k]), s1.push_back(f1[k]), sb.push_back(b.texture()[k]);
  const double coherent = correlation(s0, s1), unrelated = correlation(s0, sb);
  EXPECT_GT(coherent, 0.75) << coherent << " unrelated " << unrelated;
  EXPECT_LT(std::abs(unrelated), 0.05);
  // Frame 1 at a texel matches frame 0 at the texel that sees where the rotation about z
  // carried the texture from, better than frame 0 at the same texel.
  const Camera& cam = a.camera();
  // mult 1: from upstream (the texture moved with the flow); 0: in place; −1: from
  // downstream (it moved against the flow).
  std::vector<double> corr;
  for (const double mult : {1.0, 0.0, -1.0}) {
  std::vector<float> after, moved;
  for (size_t k = 0; k < f1.size(); ++k) {
    if (a.texel_faces()[k] < 0) continue;
    const Vec3 x = a.texel_position(k);
    const double rho = std::hypot(x.x(), x.y());
    if (rho < 0.4 || (cam.eye - x).normalized().dot(x) < 0.5) continue;  // away from poles and the rim
    const double angle = -mult * o.pixels_per_frame / a.pixels_per_unit() / rho;
    const Vec3 from(std::cos(angle) * x.x() - std::sin(angle) * x.y(), std::sin(angle) * x.x() + std::cos(angle) * x.y(),
                    x.z());
    // f0 there, bilinear between the texel centres around it.
    const Vec3 px = cam.project(from, 160, 160);
    const int i0 = static_cast<int>(std::floor(px.x() - 0.5)), j0 = static_cast<int>(std::floor(px.y() - 0.5));
    const double u = px.x() - 0.5 - i0, w = px.y() - 0.5 - j0;
    auto at = [&](int i, int j) { return static_cast<size_t>(j) * 160 + static_cast<size_t>(i); };
    if (a.texel_faces()[at(i0, j0)] < 0 || a.texel_faces()[at(i0 + 1, j0)] < 0 ||
        a.texel_faces()[at(i0, j0 + 1)] < 0 || a.texel_faces()[at(i0 + 1, j0 + 1)] < 0)
      continue;
    after.push_back(f1[k]);
    moved.push_back(static_cast<float>((1 - u) * (1 - w) * f0[at(i0, j0)] + u * (1 - w) * f0[at(i0 + 1, j0)] +
                                       (1 - u) * w * f0[at(i0, j0 + 1)] + u * w * f0[at(i0 + 1, j0 + 1)]));
  }
  ASSERT_GT(after.size(), 3000u);
  corr.push_back(correlation(after, moved));
  }
  // Streaks along the flow (and the noise cells, which stay on for several frames) keep
  // the in-place correlation high; the texture still matches its upstream place best, and
  // far better than its downstream one.
  EXPECT_GT(corr[0], corr[1] + 0.01) << corr[0] << " vs " << corr[1];
  EXPECT_GT(corr[0], corr[2] + 0.2) << corr[0] << " vs " << corr[2];
  EXPECT_GT(corr[0], 0.8);
}

TEST(SurfaceImage, CompositeShadesTheShownTextureBetweenDarkAndLit) {
  Spin s;
  TextureOptions o;
  o.size = 64;
  SurfaceImageAnimator a(s.bundle, s.field, o);
  a.advance(0.2);
  const std::vector<float> v = a.shown();
  Image lit(64, 64), dark(64, 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      lit.at(x, y) = rgb(255, 200, static_cast<std::uint8_t>(4 * x));
      dark.at(x, y) = rgb(0, 100, static_cast<std::uint8_t>(4 * x));  // blue: lit == dark
    }
  const Image img = a.composite(lit, dark);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const float g = v[static_cast<size_t>(y) * 64 + static_cast<size_t>(x)];
      ASSERT_GE(g, 0.0f);
      ASSERT_LE(g, 1.0f);
      const std::uint32_t px = img.at(x, y);
      EXPECT_EQ((px >> 16) & 255u, static_cast<std::uint32_t>(std::lround(255 * g)));
      EXPECT_EQ((px >> 8) & 255u, static_cast<std::uint32_t>(std::lround(100 + 100 * g)));
      EXPECT_EQ(px & 255u, static_cast<std::uint32_t>(4 * x));
    }
  EXPECT_NE(test::error_of([&] { a.composite(Image(32, 32), dark); }).find("32×32"), std::string::npos);
}

TEST(SurfaceImage, OpenSurfacesKeepAFiniteTexture) {
  const Mesh& mesh = test::hemisphere_mesh();
  const TangentBundle bundle(mesh);
  const Field field = sample_world(bundle, TimeSampling{0, 1, 5}, [](const Vec3& x, double t) {
    return Vec3(Vec3(1, 0.5 * t, 0) - x.dot(Vec3(1, 0.5 * t, 0)) * x);
  });
  TextureOptions o;
  o.size = 96;
  SurfaceImageAnimator a(bundle, field, o);
  for (int k = 0; k < 5; ++k) a.advance(field.time().time(k));
  for (const float v : a.texture()) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << v;
  const auto shown = a.shown();
  const auto [lo, hi] = std::minmax_element(shown.begin(), shown.end());
  EXPECT_EQ(*lo, 0.0f);
  EXPECT_EQ(*hi, 1.0f);
}

}  // namespace
}  // namespace tvf
