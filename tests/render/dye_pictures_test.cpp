// Dye drawn by the renderers (render/dye_pictures.h through the particle animations): on a
// grid the dye of a steady rotation lies on the circle through its seed and fades with
// age; on a sphere it is drawn on the surface; a seed off the domain is refused before
// anything is written.
#include "tvf/render/dye_pictures.h"

#include "support/test_fields.h"
#include "support/test_meshes.h"
#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"
#include "tvf/render/particles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

int red(std::uint32_t px) { return static_cast<int>((px >> 16) & 255u); }
int green(std::uint32_t px) { return static_cast<int>((px >> 8) & 255u); }
int blue(std::uint32_t px) { return static_cast<int>(px & 255u); }

TEST(DyePictures, ParticleDyeOfARotationIsTheCircleThroughTheSeedFadingWithAge) {
  // V = (−y, x) on [−1, 1]² over t ∈ [0, 4], 200 pixels: dye from (0.5, 0) at t = 4 is
  // the arc of radius 0.5 (50 pixels) from angle 0 (just released) to 4 rad (released at
  // t = 0), and its opacity falls from 1 to 0.3 along it.
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field =
      test::field_from(bundle, TimeSampling{0, 4, 17}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  EXPECT_EQ(dye_colour(0), 0xE8402Au);
  EXPECT_NE(dye_colour(1), dye_colour(0));
  test::TempDir dir;
  ParticleAnimationOptions o;
  o.particles.count = 1;  // one tiny leaf: the dye is what is drawn
  o.particles.size = 1;
  o.particles.image_size = 200;
  o.frames_dir = (dir / "frames").string();
  o.dye_seeds = {Vec3(0.5, 0, 0)};
  const AnimationReport r = write_particle_animation(bundle, field, o);
  ASSERT_EQ(r.frames, 17);
  const Image img = read_png((dir / "frames" / "frame_00016.png").string());
  // Over the pale blue-gray ground, red above green marks the dye.
  int on = 0, off = 0;
  double young = 0, old = 0;
  int n_young = 0, n_old = 0;
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i) {
      const std::uint32_t px = img.pixels[static_cast<size_t>(j * img.width + i)];
      const int redness = red(px) - green(px);
      if (redness < 30) continue;
      const double x = -1 + (i + 0.5) / 100.0, y = 1 - (j + 0.5) / 100.0;
      if (std::abs(std::hypot(x, y) - 0.5) > 0.06) {
        ++off;
        continue;
      }
      ++on;
      double angle = std::atan2(y, x);
      if (angle < -0.2) angle += 2 * kPi;
      if (angle > 0.3 && angle < 1.0) young += redness, ++n_young;
      if (angle > 3.0 && angle < 3.8) old += redness, ++n_old;
    }
  EXPECT_GT(on, 250);   // an arc of 4 rad × 50 pixels, 2 pixels wide
  EXPECT_LE(off, 4);    // at most the one leaf
  ASSERT_GT(n_young, 20);
  ASSERT_GT(n_old, 20);
  EXPECT_GT(young / n_young, old / n_old + 40);  // the old dye has faded
  // Without seeds no dye.
  o.dye_seeds.clear();
  o.frames_dir = (dir / "plain").string();
  write_particle_animation(bundle, field, o);
  const Image plain = read_png((dir / "plain" / "frame_00016.png").string());
  int reds = 0;
  for (const auto px : plain.pixels) reds += red(px) - green(px) >= 30;
  EXPECT_LE(reds, 4);
  // A seed outside the domain: one sentence, no frames.
  o.dye_seeds = {Vec3(0.5, 0, 0), Vec3(1.5, 0, 0)};
  o.frames_dir = (dir / "bad").string();
  EXPECT_EQ(test::error_of([&] { write_particle_animation(bundle, field, o); }),
            "the dye seed (1.5, 0) is outside the domain");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

TEST(DyePictures, SurfaceParticleDyeIsDrawnOnTheSphere) {
  const Mesh sphere = make_icosphere(3, 1.0);
  const TangentBundle bundle(sphere);
  const Field field = test::field_from(bundle, TimeSampling{0, 2, 9},
                                       [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  test::TempDir dir;
  ParticleAnimationOptions o;
  o.particles.count = 1;
  o.particles.size = 1;
  o.particles.image_size = 160;
  o.surface.direction = Vec3(0.3, 0.3, 1);  // from above: the seed's latitude z = 0.8 in view
  o.frames_dir = (dir / "frames").string();
  o.dye_seeds = {Vec3(0.6, 0, 0.8), Vec3(0, 0.6, 0.8)};
  write_particle_animation(bundle, field, o);
  const Image img = read_png((dir / "frames" / "frame_00008.png").string());
  int reds = 0, blues = 0;
  for (const auto px : img.pixels) {
    reds += red(px) > green(px) + 60 && red(px) > blue(px) + 60;
    blues += blue(px) > red(px) + 60 && blue(px) > green(px) + 20;
  }
  EXPECT_GT(reds, 60);   // seed 0's dye, red
  EXPECT_GT(blues, 60);  // seed 1's, blue
  // A seed far off the surface is refused, naming its distance.
  o.dye_seeds = {Vec3(0, 0, 2.5)};
  o.frames_dir = (dir / "bad").string();
  const std::string message = test::error_of([&] { write_particle_animation(bundle, field, o); });
  EXPECT_NE(message.find("the dye seed (0, 0, 2.5) is 1.5"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

}  // namespace
}  // namespace tvf
